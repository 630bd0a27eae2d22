//! `render --preview` in a real window: Xvfb (a virtual X display), lavapipe presenting
//! through VK_KHR_xlib_surface, the render run with `--validation` (any message, WSI
//! included, fails it). The test reads the window back from the X server (GetImage), so
//! it sees what was presented, and drives it with XTEST key presses:
//! - the colour view shows the Cornell box: red wall left, green wall right;
//! - the depth, normal and triangle-id views equal, pixel for pixel, the display twin
//!   applied to the AOVs of the EXR the render writes;
//! - S writes a snapshot equal to the twin at the film's size; Up brightens the colour view;
//! - closing the window (WM_DELETE_WINDOW) stops the render, which writes what it has;
//! - a CPU integrator's film (bpt, handed over by the render loop) shows as well.
#![cfg(x11_preview)]

use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use splitray::display::tonemap::{depth_range, tonemap_cpu, ToneParams, View};
use splitray::integrator::aov::Aovs;
use x11rb::connection::Connection;
use x11rb::protocol::xproto::{
    AtomEnum, ClientMessageEvent, ConnectionExt as _, EventMask, ImageFormat, InputFocus, Window,
    KEY_PRESS_EVENT, KEY_RELEASE_EVENT,
};
use x11rb::protocol::xtest::ConnectionExt as _;
use x11rb::rust_connection::RustConnection;

const FILM: [u32; 2] = [80, 60];

/// An Xvfb server on a display number it picks itself; killed on drop.
struct Xvfb {
    child: Child,
    display: String,
}

impl Xvfb {
    fn start() -> Self {
        let mut child = Command::new("Xvfb")
            .args([
                "-displayfd",
                "1",
                "-screen",
                "0",
                "800x600x24",
                "-nolisten",
                "tcp",
            ])
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .expect("Xvfb (apt-get install xvfb, or run `make deps`)");
        let mut line = String::new();
        BufReader::new(child.stdout.take().unwrap())
            .read_line(&mut line)
            .expect("Xvfb's display number");
        let display = format!(":{}", line.trim());
        assert!(line.trim().parse::<u32>().is_ok(), "Xvfb said {line:?}");
        Self { child, display }
    }
}

impl Drop for Xvfb {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

struct X {
    conn: RustConnection,
    root: Window,
}

impl X {
    fn connect(display: &str) -> Self {
        let (conn, screen) = x11rb::connect(Some(display)).expect("connect to Xvfb");
        let root = conn.setup().roots[screen].root;
        Self { conn, root }
    }

    fn atom(&self, name: &str) -> u32 {
        self.conn
            .intern_atom(false, name.as_bytes())
            .unwrap()
            .reply()
            .unwrap()
            .atom
    }

    fn title(&self, window: Window) -> String {
        let net_wm_name = self.atom("_NET_WM_NAME");
        for atom in [net_wm_name, AtomEnum::WM_NAME.into()] {
            let reply = self
                .conn
                .get_property(false, window, atom, AtomEnum::ANY, 0, 4096)
                .unwrap()
                .reply()
                .unwrap();
            if !reply.value.is_empty() {
                return String::from_utf8_lossy(&reply.value).into_owned();
            }
        }
        String::new()
    }

    /// The top-level window whose title starts with `splitray:`, once there is one.
    fn find_window(&self, process: &mut Child, timeout: Duration) -> Window {
        let start = Instant::now();
        loop {
            let children = self.conn.query_tree(self.root).unwrap().reply().unwrap();
            for w in children.children {
                if self.title(w).starts_with("splitray:") {
                    return w;
                }
            }
            assert!(
                process.try_wait().unwrap().is_none(),
                "splitray ended before its window appeared"
            );
            assert!(
                start.elapsed() < timeout,
                "no preview window after {timeout:?}"
            );
            std::thread::sleep(Duration::from_millis(100));
        }
    }

    fn wait_for_title(&self, window: Window, what: &str, ok: impl Fn(&str) -> bool) -> String {
        let start = Instant::now();
        loop {
            let title = self.title(window);
            if ok(&title) {
                return title;
            }
            assert!(
                start.elapsed() < Duration::from_secs(90),
                "waited for {what}; the title says {title:?}"
            );
            std::thread::sleep(Duration::from_millis(100));
        }
    }

    /// The window's pixels as the X server has them (RGB, row 0 at the top).
    fn capture(&self, window: Window) -> ([u32; 2], Vec<[u8; 3]>) {
        let geometry = self.conn.get_geometry(window).unwrap().reply().unwrap();
        let (w, h) = (geometry.width, geometry.height);
        let image = self
            .conn
            .get_image(ImageFormat::Z_PIXMAP, window, 0, 0, w, h, !0)
            .unwrap()
            .reply()
            .unwrap();
        assert_eq!(image.depth, 24);
        assert_eq!(
            image.data.len(),
            w as usize * h as usize * 4,
            "32 bits a pixel"
        );
        // Depth 24 in 32-bit little-endian pixels: B, G, R, unused.
        let rgb = image.data.chunks(4).map(|p| [p[2], p[1], p[0]]).collect();
        ([w as u32, h as u32], rgb)
    }

    /// The window's pixels once something was drawn in it. The title announces a frame
    /// as soon as it is handed to the window system; the X server shows it a little
    /// later (lavapipe presents from a thread of its own), longer on a loaded machine.
    fn capture_first_frame(&self, window: Window) -> ([u32; 2], Vec<[u8; 3]>) {
        let start = Instant::now();
        loop {
            std::thread::sleep(Duration::from_millis(600));
            let (size, pixels) = self.capture(window);
            if pixels.iter().any(|p| *p != [0, 0, 0]) {
                return (size, pixels);
            }
            assert!(
                start.elapsed() < Duration::from_secs(30),
                "the window stayed black for 30 s after its title announced a frame"
            );
        }
    }

    fn press(&self, window: Window, keysym: u32) {
        let setup = self.conn.setup();
        let (min, max) = (setup.min_keycode, setup.max_keycode);
        let map = self
            .conn
            .get_keyboard_mapping(min, max - min + 1)
            .unwrap()
            .reply()
            .unwrap();
        let per = map.keysyms_per_keycode as usize;
        let index = map
            .keysyms
            .chunks(per)
            .position(|syms| syms[0] == keysym)
            .unwrap_or_else(|| panic!("no key for keysym {keysym:#x}"));
        let keycode = min + index as u8;
        self.conn
            .set_input_focus(InputFocus::PARENT, window, x11rb::CURRENT_TIME)
            .unwrap();
        for kind in [KEY_PRESS_EVENT, KEY_RELEASE_EVENT] {
            self.conn
                .xtest_fake_input(kind, keycode, x11rb::CURRENT_TIME, self.root, 0, 0, 0)
                .unwrap();
        }
        self.conn.flush().unwrap();
    }

    /// Asks the window to close, as a window manager's close button does.
    fn close(&self, window: Window) {
        let protocols = self.atom("WM_PROTOCOLS");
        let delete = self.atom("WM_DELETE_WINDOW");
        let event = ClientMessageEvent::new(32, window, protocols, [delete, 0, 0, 0, 0]);
        self.conn
            .send_event(false, window, EventMask::NO_EVENT, event)
            .unwrap();
        self.conn.flush().unwrap();
    }
}

const XK_A: u32 = 0x61;
const XK_S: u32 = 0x73;
const XK_UP: u32 = 0xff52;

/// Samples per pixel the title reports (`… — 12/1000000 spp, …`).
fn title_spp(title: &str) -> Option<u64> {
    let (before, _) = title.split_once(" spp")?;
    let number = before.rsplit(" — ").next()?.split('/').next()?;
    number.parse().ok()
}

/// The mean RGB of window pixels over a rectangle of film pixels.
fn region_mean(
    size: [u32; 2],
    film: [u32; 2],
    pixels: &[[u8; 3]],
    film_x: std::ops::Range<u32>,
    film_y: std::ops::Range<u32>,
) -> [f64; 3] {
    let [vx, vy, vw, vh] = splitray::display::tonemap::fit(film, size);
    let mut sum = [0.0; 3];
    let mut n = 0.0;
    for y in vy..vy + vh {
        for x in vx..vx + vw {
            let (fx, fy) = ((x - vx) * film[0] / vw, (y - vy) * film[1] / vh);
            if film_x.contains(&fx) && film_y.contains(&fy) {
                let p = pixels[(y * size[0] + x) as usize];
                for c in 0..3 {
                    sum[c] += p[c] as f64;
                }
                n += 1.0;
            }
        }
    }
    sum.map(|s| s / n)
}

/// Checks that a window of `size` showing a `film`-sized Cornell box shows the left wall
/// red and the right wall green. Their albedos differ between channels by 9.7x (red
/// wall, R/G) and 3.2x (green wall, G/R); the sRGB encoding shrinks such ratios to about
/// their 2.4th root (2.6x, 1.6x), and light bounced off the white walls lowers them
/// further.
fn assert_cornell_walls(size: [u32; 2], film: [u32; 2], colour: &[[u8; 3]]) {
    let at = |lo: f64, hi: f64, n: u32| (lo * n as f64) as u32..(hi * n as f64) as u32;
    let (rows, [w, _]) = (at(0.25, 0.75, film[1]), film);
    let left = region_mean(size, film, colour, at(0.15, 0.25, w), rows.clone());
    let right = region_mean(size, film, colour, at(0.74, 0.84, w), rows);
    assert!(left[0] > 1.5 * left[1].max(left[2]), "left wall {left:?}");
    assert!(
        right[1] > 1.25 * right[0].max(right[2]),
        "right wall {right:?}"
    );
}

/// Starts `splitray render cornell-box --preview --validation` on `display`, rendering
/// a `film`-sized image with `integrator` to `dir/box.exr` until the window is closed.
fn start_preview(display: &str, dir: &Path, integrator: &str, film: [u32; 2]) -> Child {
    let [w, h] = film.map(|v| v.to_string());
    Command::new(env!("CARGO_BIN_EXE_splitray"))
        .args(["render", "cornell-box", "--preview", "--validation"])
        .args(["--integrator", integrator, "--width", &w, "--height", &h])
        .args(["--spp", "1000000", "--time", "120", "--seed", "3"])
        .arg("-o")
        .arg(dir.join("box.exr"))
        .arg("--stats")
        .arg(dir.join("box.json"))
        .env("DISPLAY", display)
        .env("RUST_LOG", "warn")
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap()
}

/// Closes the window and waits for the render to stop and write what it has: checks
/// that it succeeded and said so, and returns its stats.
fn close_and_finish(x: &X, window: Window, mut process: Child, dir: &Path) -> serde_json::Value {
    x.close(window);
    let start = Instant::now();
    while process.try_wait().unwrap().is_none() {
        assert!(
            start.elapsed() < Duration::from_secs(60),
            "still rendering a minute after the close"
        );
        std::thread::sleep(Duration::from_millis(100));
    }
    let out = process.wait_with_output().unwrap();
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(out.status.success(), "{text}");
    assert!(
        text.contains("preview window closed: the render stopped at"),
        "{text}"
    );
    let stats: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("box.json")).unwrap()).unwrap();
    assert_eq!(stats["stopped_early"], true, "{text}");
    stats
}

/// A preview window on its own Xvfb, its render past eight samples per pixel and its
/// colour view checked to show the Cornell box.
struct Session {
    xvfb: Xvfb,
    x: X,
    dir: tempfile::TempDir,
    process: Child,
    window: Window,
    /// The window's size.
    size: [u32; 2],
}

impl Session {
    fn open(integrator: &str, film: [u32; 2]) -> Self {
        let xvfb = Xvfb::start();
        let x = X::connect(&xvfb.display);
        let dir = tempfile::tempdir().unwrap();
        let mut process = start_preview(&xvfb.display, dir.path(), integrator, film);
        let window = x.find_window(&mut process, Duration::from_secs(60));
        x.wait_for_title(window, "eight samples per pixel", |t| {
            title_spp(t).is_some_and(|spp| spp >= 8)
        });
        let (size, colour) = x.capture_first_frame(window);
        assert_eq!(size, splitray::preview::window_size(film));
        assert_cornell_walls(size, film, &colour);
        Self {
            xvfb,
            x,
            dir,
            process,
            window,
            size,
        }
    }
}

/// What the display twin shows of the EXR's AOVs in `view` at `size`.
fn twin_view(aovs: &Aovs, view: View, size: [u32; 2]) -> Vec<[u8; 3]> {
    let params = ToneParams::new(FILM, size, view, 1.0, false, depth_range(&aovs.depth));
    let film = vec![[0.0f32; 4]; (FILM[0] * FILM[1]) as usize];
    tonemap_cpu(&params, &film, aovs)
        .iter()
        .map(|p| [*p as u8, (p >> 8) as u8, (p >> 16) as u8])
        .collect()
}

fn assert_same_image(what: &str, got: &[[u8; 3]], want: &[[u8; 3]], width: u32) {
    assert_eq!(got.len(), want.len(), "{what}: size");
    let wrong: Vec<usize> = (0..got.len()).filter(|&i| got[i] != want[i]).collect();
    assert!(
        wrong.is_empty(),
        "{what}: {} pixels differ, first at ({}, {}): shown {:?}, twin {:?}",
        wrong.len(),
        wrong[0] as u32 % width,
        wrong[0] as u32 / width,
        got[wrong[0]],
        want[wrong[0]]
    );
}

fn read_png(path: &Path) -> ([u32; 2], Vec<[u8; 3]>) {
    let decoder = png::Decoder::new(std::fs::File::open(path).unwrap());
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut buf).unwrap();
    assert_eq!(info.color_type, png::ColorType::Rgb);
    let rgb = buf[..info.buffer_size()]
        .chunks(3)
        .map(|p| [p[0], p[1], p[2]])
        .collect();
    ([info.width, info.height], rgb)
}

fn snapshot_file(dir: &Path) -> Option<PathBuf> {
    std::fs::read_dir(dir)
        .ok()?
        .flatten()
        .map(|e| e.path())
        .find(|p| {
            p.file_name()
                .is_some_and(|n| n.to_string_lossy().ends_with("spp-triangle-id.png"))
        })
}

#[test]
fn the_preview_window_shows_the_render_its_aovs_and_stops_it_when_closed() {
    let Session {
        xvfb,
        x,
        dir,
        process,
        window,
        size,
    } = Session::open("pt", FILM);

    let mut views = Vec::new();
    for view in [View::Depth, View::Normal, View::TriangleId] {
        x.press(window, XK_A);
        x.wait_for_title(window, view.name(), |t| t.ends_with(view.name()));
        std::thread::sleep(Duration::from_millis(600));
        views.push((view, x.capture(window).1));
    }
    x.press(window, XK_S);
    let start = Instant::now();
    let snapshot = loop {
        if let Some(path) = snapshot_file(dir.path()) {
            break path;
        }
        assert!(
            start.elapsed() < Duration::from_secs(30),
            "no snapshot written"
        );
        std::thread::sleep(Duration::from_millis(100));
    };

    // Back to colour, one stop brighter.
    x.press(window, XK_A);
    x.wait_for_title(window, "colour", |t| t.ends_with("colour"));
    std::thread::sleep(Duration::from_millis(600));
    let before = region_mean(size, FILM, &x.capture(window).1, 0..80, 0..60);
    x.press(window, XK_UP);
    x.press(window, XK_UP);
    x.wait_for_title(window, "+1 EV", |t| t.ends_with("colour +1.0 EV"));
    std::thread::sleep(Duration::from_millis(600));
    let after = region_mean(size, FILM, &x.capture(window).1, 0..80, 0..60);
    let brightness = |m: [f64; 3]| m.iter().sum::<f64>();
    assert!(
        brightness(after) > 1.15 * brightness(before),
        "one stop brighter: {before:?} → {after:?}"
    );

    let stats = close_and_finish(&x, window, process, dir.path());
    assert!(stats["spp"].as_u64().unwrap() >= 8);

    // The AOV views, shown and snapshotted, are the twin's image of the EXR's AOVs.
    let (film, _) = splitray::film::read_exr(dir.path().join("box.exr")).unwrap();
    let aovs = Aovs {
        depth: film.depth.clone().unwrap(),
        triangle_id: film.triangle_id.clone().unwrap(),
        normal: film.normal.clone().unwrap(),
    };
    for (view, shown) in &views {
        let want = twin_view(&aovs, *view, size);
        assert_same_image(&format!("{} view", view.name()), shown, &want, size[0]);
    }
    let (snapshot_size, snapshot) = read_png(&snapshot);
    assert_eq!(snapshot_size, FILM);
    assert_same_image(
        "triangle-id snapshot",
        &snapshot,
        &twin_view(&aovs, View::TriangleId, FILM),
        FILM[0],
    );
    drop(xvfb);
}

#[test]
fn the_preview_window_shows_a_cpu_integrators_film() {
    // bpt keeps its film on the host: the render loop hands it over after every batch
    // and the window uploads it before tone-mapping it.
    let session = Session::open("bpt", [40, 30]);
    close_and_finish(
        &session.x,
        session.window,
        session.process,
        session.dir.path(),
    );
    drop(session.xvfb);
}

#[test]
fn preview_without_a_display_is_refused_before_any_work() {
    let dir = tempfile::tempdir().unwrap();
    let output = dir.path().join("none.exr");
    let out = Command::new(env!("CARGO_BIN_EXE_splitray"))
        .args(["render", "cornell-box", "--preview", "-o"])
        .arg(&output)
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(text.contains("--preview needs an X11 display"), "{text}");
    assert!(
        std::fs::read_dir(dir.path()).unwrap().next().is_none(),
        "nothing written"
    );

    // A display that no server answers for.
    let absent = (1900..2000)
        .find(|n| !Path::new(&format!("/tmp/.X11-unix/X{n}")).exists())
        .unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_splitray"))
        .args(["render", "cornell-box", "--preview", "-o"])
        .arg(&output)
        .env("DISPLAY", format!(":{absent}"))
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(
        text.contains(&format!("--preview: cannot open the X display ':{absent}'")),
        "{text}"
    );
    assert!(
        std::fs::read_dir(dir.path()).unwrap().next().is_none(),
        "nothing written"
    );
}
