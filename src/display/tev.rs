//! `--display-server HOST:PORT`: the render streamed to the tev image viewer over tev's IPC
//! protocol (TCP; packets encoded by the `tev_client` crate), so that a render on a
//! headless server can be watched from a desktop running `tev --hostname HOST:PORT`.
//!
//! As pbrt-v4's display server client does, a thread of its own sends, once per
//! connection, a CreateImage packet (R, G, B and the AOV channels, named as in the EXR),
//! the AOVs, and then about four times a second an UpdateImage packet for each tile of
//! the image whose pixels changed since they were last sent; the last update is the
//! finished film, the values the EXR holds. A film on the GPU is copied to the host for
//! this on the thread's own time ([`FilmReader`]), not the render's. A listener that is
//! not there or goes away costs the render nothing: the thread warns once, retries the
//! connection about once a second, and sends the whole image again when it is back.

use std::net::{SocketAddr, TcpStream, ToSocketAddrs};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use tev_client::{PacketCreateImage, PacketUpdateImage, TevClient};

use super::feed::{FeedInfo, FeedSnapshot, FilmFeed};
use super::readback::FilmReader;
use crate::film::exr_out::{CHANNELS_NORMAL, CHANNEL_DEPTH, CHANNEL_TRIANGLE_ID};

/// Side of the square tiles updates are sent in.
pub const TILE: u32 = 64;
/// Seconds between two updates.
const UPDATE_INTERVAL: Duration = Duration::from_millis(250);
/// Seconds between two connection attempts while the listener is away.
const RECONNECT_INTERVAL: Duration = Duration::from_secs(1);
/// How long one connection attempt or one packet may block.
const NETWORK_TIMEOUT: Duration = Duration::from_secs(3);

const RGB: [&str; 3] = ["R", "G", "B"];

/// Checks a `HOST:PORT` address (the port a number) before any work.
pub fn parse_address(spec: &str) -> Result<String, String> {
    let Some((host, port)) = spec.rsplit_once(':') else {
        return Err(format!("expected HOST:PORT, got '{spec}'"));
    };
    if host.is_empty() {
        return Err(format!("'{spec}' names no host"));
    }
    port.parse::<u16>()
        .map_err(|_| format!("'{port}' in '{spec}' is not a port number"))?;
    Ok(spec.to_string())
}

/// One tile of an image: `[x, y, width, height]`.
pub type Tile = [u32; 4];

/// The tiles of a `width × height` image, row by row (the last ones cut to fit).
pub fn tiles(width: u32, height: u32) -> Vec<Tile> {
    let mut out = Vec::new();
    for y in (0..height).step_by(TILE as usize) {
        for x in (0..width).step_by(TILE as usize) {
            out.push([x, y, TILE.min(width - x), TILE.min(height - y)]);
        }
    }
    out
}

/// Whether any pixel of `tile` differs, bit for bit (a NaN that stays NaN is no change),
/// between two images of `width` columns.
pub fn tile_changed(old: &[[f32; 3]], new: &[[f32; 3]], width: u32, tile: Tile) -> bool {
    let [x, y, w, h] = tile;
    (y..y + h).any(|row| {
        let start = (row * width + x) as usize;
        let range = start..start + w as usize;
        old[range.clone()]
            .iter()
            .zip(&new[range])
            .any(|(a, b)| a.map(f32::to_bits) != b.map(f32::to_bits))
    })
}

/// A tile's pixels, channel values interleaved (`[c0, c1, …]` per pixel).
fn tile_values<const N: usize>(image: &[[f32; N]], width: u32, tile: Tile) -> Vec<f32> {
    let [x, y, w, h] = tile;
    let mut out = Vec::with_capacity((w * h) as usize * N);
    for row in y..y + h {
        let start = (row * width + x) as usize;
        for pixel in &image[start..start + w as usize] {
            out.extend_from_slice(pixel);
        }
    }
    out
}

/// What the stream did, for the render's summary.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct TevReport {
    pub address: String,
    /// Connections the listener accepted (more than one: it went away and came back).
    pub connections: u32,
    /// UpdateImage packets sent.
    pub updates: u64,
    /// The finished film reached the listener.
    pub final_sent: bool,
}

/// The thread streaming one render to tev.
pub struct TevStream {
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<TevReport>>,
}

impl TevStream {
    /// Starts streaming the film of `feed` to tev at `address` (see [`parse_address`]),
    /// as the image `image_name`.
    pub fn start(
        address: String,
        image_name: String,
        feed: Arc<FilmFeed>,
    ) -> std::io::Result<Self> {
        let stop = Arc::new(AtomicBool::new(false));
        let thread_stop = stop.clone();
        let thread = std::thread::Builder::new()
            .name("tev".into())
            .spawn(move || {
                let mut sender = Sender::new(address, image_name);
                sender.run(&feed, &thread_stop);
                sender.report
            })?;
        Ok(Self {
            stop,
            thread: Some(thread),
        })
    }

    /// Waits for the stream to send the finished film (or to give up on the listener)
    /// and returns what it did.
    pub fn finish(mut self) -> TevReport {
        self.thread
            .take()
            .and_then(|t| t.join().ok())
            .unwrap_or_default()
    }
}

impl Drop for TevStream {
    /// A render that failed publishes no finished film: stop the stream instead.
    fn drop(&mut self) {
        if let Some(thread) = self.thread.take() {
            self.stop.store(true, Ordering::SeqCst);
            let _ = thread.join();
        }
    }
}

/// A connection to tev and what it has been sent.
struct Connection {
    client: TevClient,
    /// The image as last sent (for the tiles that changed); `None` before the first.
    sent: Option<Vec<[f32; 3]>>,
}

struct Sender {
    address: String,
    image_name: String,
    connection: Option<Connection>,
    next_attempt: Instant,
    /// The listener was reported missing and has not come back since.
    warned: bool,
    reader: Option<FilmReader>,
    report: TevReport,
}

impl Sender {
    fn new(address: String, image_name: String) -> Self {
        Self {
            report: TevReport {
                address: address.clone(),
                ..Default::default()
            },
            address,
            image_name,
            connection: None,
            next_attempt: Instant::now(),
            warned: false,
            reader: None,
        }
    }

    fn run(&mut self, feed: &FilmFeed, stop: &AtomicBool) {
        let mut seen = 0;
        let mut last_update = Instant::now() - UPDATE_INTERVAL;
        loop {
            let wait = UPDATE_INTERVAL.saturating_sub(last_update.elapsed());
            let snapshot = feed.wait_newer(seen, wait);
            seen = snapshot.version;
            if stop.load(Ordering::SeqCst) {
                return;
            }
            if !snapshot.finished && last_update.elapsed() < UPDATE_INTERVAL {
                continue;
            }
            last_update = Instant::now();
            let Some(info) = snapshot.info.clone() else {
                continue;
            };
            if self.connection.is_none() && (snapshot.finished || self.retry_due()) {
                self.connect(&info);
            }
            // The film is read only for a viewer that is there.
            let image = match self.connection.is_some() {
                true => self.current_image(&info, &snapshot),
                false => None,
            };
            let sent = image.is_some_and(|image| self.send_changes(&info, &image));
            if snapshot.finished {
                self.report.final_sent = sent;
                return;
            }
        }
    }

    /// The film now: the finished one, the GPU's, or the latest the render published.
    fn current_image(&mut self, info: &FeedInfo, snapshot: &FeedSnapshot) -> Option<Vec<[f32; 3]>> {
        if snapshot.finished {
            return snapshot.host.as_ref().map(|h| h.mean.clone());
        }
        if let Some(film) = &info.device_film {
            if self.reader.is_none() {
                match FilmReader::new(film) {
                    Ok(reader) => self.reader = Some(reader),
                    Err(e) => log::warn!("display server: cannot read the film: {e}"),
                }
            }
            if let Some(reader) = &self.reader {
                match reader.read_mean(film) {
                    Ok(mean) => return Some(mean),
                    Err(e) => log::warn!("display server: cannot read the film: {e}"),
                }
            }
        }
        snapshot.host.as_ref().map(|h| h.mean.clone())
    }

    fn retry_due(&self) -> bool {
        Instant::now() >= self.next_attempt
    }

    /// Connects and sends what a new viewer needs: CreateImage and the AOVs.
    fn connect(&mut self, info: &FeedInfo) {
        self.next_attempt = Instant::now() + RECONNECT_INTERVAL;
        let stream = match open(&self.address) {
            Ok(s) => s,
            Err(e) => {
                self.lost(&e);
                return;
            }
        };
        // Counted as soon as the listener accepted: one that goes away during the
        // introduction was still reached, and the summary must say it went away.
        let reconnection = self.warned || self.report.connections > 0;
        self.report.connections += 1;
        let mut connection = Connection {
            client: TevClient::wrap(stream),
            sent: None,
        };
        if let Err(e) = self.introduce(&mut connection, info) {
            self.lost(&e);
            return;
        }
        if reconnection {
            crate::errln!("display server {}: connected", self.address);
        }
        self.warned = false;
        self.connection = Some(connection);
    }

    fn introduce(&mut self, connection: &mut Connection, info: &FeedInfo) -> std::io::Result<()> {
        let mut channels: Vec<&str> = RGB.to_vec();
        channels.push(CHANNEL_DEPTH);
        channels.extend(CHANNELS_NORMAL);
        channels.push(CHANNEL_TRIANGLE_ID);
        connection.client.send(PacketCreateImage {
            image_name: &self.image_name,
            grab_focus: true,
            width: info.width,
            height: info.height,
            channel_names: &channels,
        })?;
        // The AOVs do not change: sent once per connection. Triangle ids travel as
        // floats (exact below 2^24; a miss, u32::MAX, shows as 4.3e9).
        let aovs: Vec<[f32; 5]> = (0..info.aovs.depth.len())
            .map(|i| {
                let n = info.aovs.normal[i];
                [
                    info.aovs.depth[i],
                    n[0],
                    n[1],
                    n[2],
                    info.aovs.triangle_id[i] as f32,
                ]
            })
            .collect();
        let names = [
            CHANNEL_DEPTH,
            CHANNELS_NORMAL[0],
            CHANNELS_NORMAL[1],
            CHANNELS_NORMAL[2],
            CHANNEL_TRIANGLE_ID,
        ];
        for tile in tiles(info.width, info.height) {
            send_tile(
                &mut connection.client,
                &self.image_name,
                &names,
                &aovs,
                info.width,
                tile,
            )?;
        }
        Ok(())
    }

    /// Sends the tiles of `image` that differ from what the viewer has. Returns whether
    /// the viewer has the whole image now.
    fn send_changes(&mut self, info: &FeedInfo, image: &[[f32; 3]]) -> bool {
        let Some(connection) = self.connection.as_mut() else {
            return false;
        };
        let mut result = Ok(());
        for tile in tiles(info.width, info.height) {
            let changed = connection
                .sent
                .as_ref()
                .is_none_or(|sent| tile_changed(sent, image, info.width, tile));
            if !changed {
                continue;
            }
            result = send_tile(
                &mut connection.client,
                &self.image_name,
                &RGB,
                image,
                info.width,
                tile,
            );
            if result.is_err() {
                break;
            }
            self.report.updates += 1;
        }
        match result {
            Ok(()) => {
                connection.sent = Some(image.to_vec());
                true
            }
            Err(e) => {
                self.connection = None;
                self.lost(&e);
                false
            }
        }
    }

    /// Notes a listener that is away: warned once until it is back.
    fn lost(&mut self, error: &std::io::Error) {
        if !self.warned {
            crate::errln!(
                "display server {}: {error}; the render goes on and the connection is retried",
                self.address
            );
            self.warned = true;
        }
    }
}

/// Opens a connection, bounded in time, with writes that give up after a while.
fn open(address: &str) -> std::io::Result<TcpStream> {
    let addresses: Vec<SocketAddr> = address.to_socket_addrs()?.collect();
    let mut last = std::io::Error::new(std::io::ErrorKind::NotFound, "the host has no address");
    for addr in addresses {
        match TcpStream::connect_timeout(&addr, NETWORK_TIMEOUT) {
            Ok(stream) => {
                stream.set_write_timeout(Some(NETWORK_TIMEOUT))?;
                stream.set_nodelay(true)?;
                return Ok(stream);
            }
            Err(e) => last = e,
        }
    }
    Err(last)
}

fn send_tile<const N: usize>(
    client: &mut TevClient,
    image_name: &str,
    channels: &[&str; N],
    image: &[[f32; N]],
    width: u32,
    tile: Tile,
) -> std::io::Result<()> {
    let data = tile_values(image, width, tile);
    let offsets: [u64; N] = std::array::from_fn(|c| c as u64);
    client.send(PacketUpdateImage {
        image_name,
        grab_focus: false,
        channel_names: channels,
        channel_offsets: &offsets,
        channel_strides: &[N as u64; N],
        x: tile[0],
        y: tile[1],
        width: tile[2],
        height: tile[3],
        data: &data,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn addresses_need_a_host_and_a_port() {
        assert_eq!(parse_address("127.0.0.1:14158").unwrap(), "127.0.0.1:14158");
        assert!(parse_address("localhost:1").is_ok());
        assert!(parse_address("[::1]:14158").is_ok());
        assert!(parse_address("localhost").is_err());
        assert!(parse_address(":14158").is_err());
        assert!(parse_address("host:port").is_err());
        assert!(parse_address("host:70000").is_err());
    }

    #[test]
    fn tiles_cover_the_image_once() {
        for (w, h) in [(1, 1), (64, 64), (65, 1), (200, 130), (3, 300)] {
            let mut covered = vec![0u32; (w * h) as usize];
            for [x, y, tw, th] in tiles(w, h) {
                assert!(tw >= 1 && th >= 1 && tw <= TILE && th <= TILE);
                for row in y..y + th {
                    for col in x..x + tw {
                        covered[(row * w + col) as usize] += 1;
                    }
                }
            }
            assert!(covered.iter().all(|&c| c == 1), "{w}x{h}");
        }
        assert!(tiles(0, 5).is_empty());
    }

    #[test]
    fn only_tiles_with_a_changed_pixel_count_as_changed() {
        let (w, h) = (130u32, 70u32);
        let old = vec![[0.5f32; 3]; (w * h) as usize];
        let mut new = old.clone();
        // One pixel in the last tile of the first row of tiles; a NaN that stays NaN
        // (same bits) is no change.
        new[(10 * w + 129) as usize][1] = 0.25;
        let mut with_nan = old.clone();
        with_nan[0] = [f32::NAN; 3];
        let all = tiles(w, h);
        let changed: Vec<_> = all
            .iter()
            .filter(|t| tile_changed(&old, &new, w, **t))
            .collect();
        assert_eq!(changed, vec![&[128, 0, 2, 64]]);
        assert!(!all
            .iter()
            .any(|t| tile_changed(&with_nan, &with_nan, w, *t)));
        assert!(tile_changed(&old, &with_nan, w, all[0]));
        assert_eq!(
            tile_values(&new, w, [128, 10, 2, 1]),
            vec![0.5, 0.5, 0.5, 0.5, 0.25, 0.5]
        );
    }
}
