//! `render --display-server HOST:PORT`: a tev listener inside the test receives the
//! stream and checks it packet by packet, with a parser written from tev's IPC format
//! (a u32 length that counts itself, a type byte, NUL-terminated strings, little-endian
//! numbers; CreateImage = 4, UpdateImageV3 = 6): a well-formed CreateImage first, then
//! UpdateImage packets of tiles inside the image whose data matches their offsets and
//! strides, progressive (tiles updated more than once), and the last pixels equal to the
//! EXR's. A listener that goes away, or is never there, does not stop the render.

use crate::common;

use std::collections::HashMap;
use std::io::Read;
use std::net::TcpListener;

use common::cli::{printed, splitray};

#[derive(Debug)]
enum Packet {
    Create {
        grab_focus: bool,
        name: String,
        width: i32,
        height: i32,
        channels: Vec<String>,
    },
    Update {
        name: String,
        channels: Vec<String>,
        rect: [i32; 4],
        /// Per channel, the tile's values in row order.
        values: Vec<Vec<f32>>,
    },
}

struct Cursor<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl Cursor<'_> {
    fn take(&mut self, n: usize) -> &[u8] {
        assert!(self.at + n <= self.bytes.len(), "packet ends early");
        self.at += n;
        &self.bytes[self.at - n..self.at]
    }
    fn u8(&mut self) -> u8 {
        self.take(1)[0]
    }
    fn i32(&mut self) -> i32 {
        i32::from_le_bytes(self.take(4).try_into().unwrap())
    }
    fn i64(&mut self) -> i64 {
        i64::from_le_bytes(self.take(8).try_into().unwrap())
    }
    fn string(&mut self) -> String {
        let end = self.bytes[self.at..]
            .iter()
            .position(|&b| b == 0)
            .expect("a NUL-terminated string");
        let s = String::from_utf8(self.bytes[self.at..self.at + end].to_vec()).unwrap();
        self.at += end + 1;
        s
    }
    fn bool(&mut self) -> bool {
        match self.u8() {
            0 => false,
            1 => true,
            b => panic!("bool byte {b}"),
        }
    }
}

fn parse(stream: &[u8]) -> Vec<Packet> {
    let mut packets = Vec::new();
    let mut at = 0;
    while at < stream.len() {
        assert!(at + 5 <= stream.len(), "a truncated packet header at {at}");
        let len = u32::from_le_bytes(stream[at..at + 4].try_into().unwrap()) as usize;
        assert!(
            len >= 5 && at + len <= stream.len(),
            "packet length {len} at {at}"
        );
        let mut c = Cursor {
            bytes: &stream[at..at + len],
            at: 5,
        };
        let packet = match stream[at + 4] {
            4 => {
                let grab_focus = c.bool();
                let name = c.string();
                let (width, height) = (c.i32(), c.i32());
                let n = c.i32();
                let channels = (0..n).map(|_| c.string()).collect();
                Packet::Create {
                    grab_focus,
                    name,
                    width,
                    height,
                    channels,
                }
            }
            6 => {
                let _grab_focus = c.bool();
                let name = c.string();
                let n = c.i32() as usize;
                let channels: Vec<String> = (0..n).map(|_| c.string()).collect();
                let rect = [c.i32(), c.i32(), c.i32(), c.i32()];
                let offsets: Vec<i64> = (0..n).map(|_| c.i64()).collect();
                let strides: Vec<i64> = (0..n).map(|_| c.i64()).collect();
                let pixels = (rect[2] * rect[3]) as i64;
                assert!(pixels > 0, "an empty update");
                let count = (0..n)
                    .map(|i| offsets[i] + (pixels - 1) * strides[i] + 1)
                    .max()
                    .unwrap() as usize;
                let data: Vec<f32> = c
                    .take(count * 4)
                    .chunks(4)
                    .map(|b| f32::from_le_bytes(b.try_into().unwrap()))
                    .collect();
                let values = (0..n)
                    .map(|i| {
                        (0..pixels)
                            .map(|p| data[(offsets[i] + p * strides[i]) as usize])
                            .collect()
                    })
                    .collect();
                Packet::Update {
                    name,
                    channels,
                    rect,
                    values,
                }
            }
            t => panic!("unexpected packet type {t}"),
        };
        assert_eq!(c.at, len, "the packet's length covers exactly its fields");
        packets.push(packet);
        at += len;
    }
    packets
}

#[test]
fn tev_receives_a_well_formed_progressive_stream_ending_in_the_exrs_pixels() {
    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    let address = listener.local_addr().unwrap().to_string();
    let receiver = std::thread::spawn(move || {
        let (mut socket, _) = listener.accept().unwrap();
        let mut bytes = Vec::new();
        socket.read_to_end(&mut bytes).unwrap();
        bytes
    });
    let dir = tempfile::tempdir().unwrap();
    let out = splitray(
        &[
            "render",
            "cornell-box",
            "--integrator",
            "pt",
            "--width",
            "70",
            "--height",
            "40",
            "--spp",
            "1000000",
            "--time",
            "4",
            "--validation",
            "--display-server",
            &address,
            "-o",
            "box.exr",
        ],
        dir.path(),
    );
    assert!(out.status.success(), "{}", printed(&out));
    assert!(
        printed(&out).contains("sent the finished image"),
        "{}",
        printed(&out)
    );
    let packets = parse(&receiver.join().unwrap());

    let Packet::Create {
        grab_focus,
        name,
        width,
        height,
        channels,
    } = &packets[0]
    else {
        panic!("the stream starts with CreateImage, not {:?}", packets[0]);
    };
    assert!(grab_focus);
    assert_eq!(name, "box.exr");
    assert_eq!((*width, *height), (70, 40));
    let expected = [
        "R",
        "G",
        "B",
        "depth.Z",
        "normal.X",
        "normal.Y",
        "normal.Z",
        "triangle_id",
    ];
    assert_eq!(channels, &expected);

    // Replay the updates into an image of every channel, counting updates per tile.
    let (w, h) = (*width as usize, *height as usize);
    let mut image: HashMap<&str, Vec<f32>> = expected
        .iter()
        .map(|c| (*c, vec![f32::NAN; w * h]))
        .collect();
    let mut rgb_updates: HashMap<[i32; 4], u32> = HashMap::new();
    for packet in &packets[1..] {
        let Packet::Update {
            name,
            channels,
            rect,
            values,
        } = packet
        else {
            panic!("only the first packet creates the image: {packet:?}");
        };
        assert_eq!(name, "box.exr");
        let [x, y, tw, th] = *rect;
        assert!(x >= 0 && y >= 0 && tw > 0 && th > 0, "{rect:?}");
        assert!(
            x + tw <= *width && y + th <= *height,
            "{rect:?} outside the image"
        );
        for (channel, values) in channels.iter().zip(values) {
            let plane = image
                .get_mut(channel.as_str())
                .unwrap_or_else(|| panic!("an update of unknown channel {channel}"));
            for (i, v) in values.iter().enumerate() {
                let (px, py) = (x as usize + i % tw as usize, y as usize + i / tw as usize);
                plane[py * w + px] = *v;
            }
        }
        if channels[0] == "R" {
            *rgb_updates.entry(*rect).or_default() += 1;
        }
    }
    assert!(
        rgb_updates.values().any(|&n| n >= 2),
        "the image was updated as it converged: {rgb_updates:?}"
    );

    let (film, _) = splitray::film::read_exr(dir.path().join("box.exr")).unwrap();
    let channel = |name: &str, i: usize| image[name][i];
    let (depth, normal) = (film.depth.as_ref().unwrap(), film.normal.as_ref().unwrap());
    let triangle_id = film.triangle_id.as_ref().unwrap();
    assert_eq!(depth.len(), w * h);
    for (i, d) in depth.iter().enumerate() {
        let mean = film.mean_rgb(i);
        let shown = [channel("R", i), channel("G", i), channel("B", i)];
        assert_eq!(
            shown.map(f32::to_bits),
            mean.map(f32::to_bits),
            "pixel {i}: tev has {shown:?}, the EXR {mean:?}"
        );
        assert_eq!(channel("depth.Z", i).to_bits(), d.to_bits());
        let shown_n = ["normal.X", "normal.Y", "normal.Z"].map(|c| channel(c, i));
        assert_eq!(shown_n.map(f32::to_bits), normal[i].map(f32::to_bits));
        assert_eq!(channel("triangle_id", i), triangle_id[i] as f32);
    }
}

#[test]
fn a_listener_that_goes_away_or_is_never_there_does_not_stop_the_render() {
    // The CPU integrator's film reaches the stream from the render loop, not the GPU.
    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    let address = listener.local_addr().unwrap().to_string();
    let receiver = std::thread::spawn(move || {
        let (mut socket, _) = listener.accept().unwrap();
        let mut header = [0u8; 5];
        socket.read_exact(&mut header).unwrap();
        // The listener reads the CreateImage packet's header and goes away, listener and
        // all: the stream's later sends and reconnections fail.
        header[4]
    });
    let dir = tempfile::tempdir().unwrap();
    let out = splitray(
        &[
            "render",
            "cornell-box",
            "--integrator",
            "bpt",
            "--width",
            "24",
            "--height",
            "16",
            "--spp",
            "1000000",
            "--time",
            "3",
            "--display-server",
            &address,
            "-o",
            "gone.exr",
        ],
        dir.path(),
    );
    assert_eq!(receiver.join().unwrap(), 4, "CreateImage first");
    assert!(out.status.success(), "{}", printed(&out));
    let t = printed(&out);
    assert!(t.contains("the render goes on"), "{t}");
    assert!(t.contains("gone before the finished image"), "{t}");
    assert!(dir.path().join("gone.exr").is_file());

    // Nobody listening at all: a port that was free a moment ago.
    let free = TcpListener::bind("127.0.0.1:0").unwrap();
    let address = free.local_addr().unwrap().to_string();
    drop(free);
    let out = splitray(
        &[
            "render",
            "cornell-box",
            "--width",
            "24",
            "--height",
            "16",
            "--spp",
            "4",
            "--display-server",
            &address,
            "-o",
            "alone.exr",
        ],
        dir.path(),
    );
    assert!(out.status.success(), "{}", printed(&out));
    assert!(printed(&out).contains("never reached"), "{}", printed(&out));
    assert!(dir.path().join("alone.exr").is_file());

    // A malformed address is refused before any work.
    let out = splitray(
        &["render", "--display-server", "localhost", "-o", "bad.exr"],
        dir.path(),
    );
    assert!(!out.status.success());
    assert!(
        printed(&out).contains("--display-server: expected HOST:PORT"),
        "{}",
        printed(&out)
    );
    assert!(!dir.path().join("bad.exr").exists());
}
