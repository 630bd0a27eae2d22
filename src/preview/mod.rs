//! `render --preview`: a window that shows the film converging, presented through a
//! Vulkan swapchain on the render's own device (winit on X11, ash-window).
//!
//! The window lives on a thread of its own (winit's event loop, made with `any_thread`),
//! so that it stays responsive while the render loop runs batches of passes. In order:
//! [`Preview::open`] opens the event loop and the window, or fails at once without a
//! display; the device is then opened with the window system's surface extensions
//! ([`Preview::surface_extensions`]); [`Preview::attach`] makes the surface and swapchain
//! and starts the frames (about four a second, from the [`FilmFeed`]). Closing the window
//! sets [`Preview::closed`], which the render's stop check reads; [`Preview::close`] ends
//! the thread.
//!
//! Frames read the integrator's film on the GPU where it keeps one (`pt` and the ray
//! workloads), in order with the passes on the main stream; the CPU integrators (`bpt`,
//! `light`) publish their film after every batch, and the window uploads it. Keys: ↑/↓
//! or +/− exposure by half stops, 0 resets it; A or Tab cycles colour, depth, normal and
//! triangle id; S writes a snapshot of the view beside the output; Escape or Q closes.

mod app;
mod presenter;

use std::ffi::CStr;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{mpsc, Arc};
use std::thread::JoinHandle;
use std::time::Duration;

use winit::event_loop::{EventLoop, EventLoopProxy};
use winit::platform::x11::EventLoopBuilderExtX11;

use crate::display::FilmFeed;
use crate::vk::{self, Gpu};
use app::{App, Command};

/// What the window shows and where snapshots go.
#[derive(Clone, Debug)]
pub struct PreviewOptions {
    /// The scene's name, for the title.
    pub name: String,
    /// The film's width and height.
    pub film: [u32; 2],
    /// Snapshots are written as `STEM.snapshot-<spp>spp-<view>.png`.
    pub snapshot_stem: PathBuf,
}

#[derive(Debug, thiserror::Error)]
pub enum PreviewError {
    #[error(
        "--preview needs an X11 display, and DISPLAY is not set: run it on a desktop, over \
         `ssh -X`, or under Xvfb (--display-server HOST:PORT shows a headless render in tev)"
    )]
    NoDisplay,
    #[error("--preview: {0}")]
    Window(String),
}

/// How long opening or attaching the window may take before it counts as failed.
const WINDOW_TIMEOUT: Duration = Duration::from_secs(60);

/// The window's size for a film of `film` pixels: small films magnified by a whole
/// factor to about 512 pixels, large ones shrunk to fit 1280 × 1024.
pub fn window_size(film: [u32; 2]) -> [u32; 2] {
    let [w, h] = film.map(|v| v.max(1));
    let long = w.max(h);
    if long < 512 {
        let k = (512 / long).max(1);
        return [w * k, h * k];
    }
    let scale = (1280.0 / w as f64).min(1024.0 / h as f64).min(1.0);
    [w, h].map(|v| ((v as f64 * scale).round() as u32).max(1))
}

/// The preview window of one render.
pub struct Preview {
    proxy: EventLoopProxy<Command>,
    thread: Option<JoinHandle<()>>,
    closed: Arc<AtomicBool>,
    extensions: Vec<&'static CStr>,
}

impl Preview {
    /// Opens the window's event loop (and then the window) on a thread of its own; fails
    /// at once when there is no display to open it on.
    pub fn open(options: PreviewOptions) -> Result<Self, PreviewError> {
        if std::env::var_os("DISPLAY").is_none_or(|d| d.is_empty()) {
            return Err(PreviewError::NoDisplay);
        }
        let closed = Arc::new(AtomicBool::new(false));
        let app_closed = closed.clone();
        let (opened, open_result) = mpsc::channel();
        let thread = std::thread::Builder::new()
            .name("preview".into())
            .spawn(move || {
                let event_loop = match EventLoop::<Command>::with_user_event()
                    .with_any_thread(true)
                    .build()
                {
                    Ok(event_loop) => event_loop,
                    Err(e) => {
                        let display = std::env::var("DISPLAY").unwrap_or_default();
                        // winit's message leads with its own source location: keep the
                        // reason at its end.
                        let message = e.to_string();
                        let reason = message.rsplit(": ").next().unwrap_or(&message);
                        let _ = opened.send(Err(format!(
                            "cannot open the X display '{display}': {reason}"
                        )));
                        return;
                    }
                };
                let extensions = match vk::surface_extensions(&event_loop) {
                    Ok(extensions) => extensions,
                    Err(e) => {
                        let _ = opened.send(Err(e.to_string()));
                        return;
                    }
                };
                let _ = opened.send(Ok((event_loop.create_proxy(), extensions)));
                let mut app = App::new(options, app_closed);
                if let Err(e) = event_loop.run_app(&mut app) {
                    crate::errln!("preview: the window's event loop failed: {e}");
                }
            })
            .map_err(|e| PreviewError::Window(format!("cannot start its thread: {e}")))?;
        let (proxy, extensions) = open_result
            .recv_timeout(WINDOW_TIMEOUT)
            .map_err(|_| PreviewError::Window("the window system did not answer".into()))?
            .map_err(PreviewError::Window)?;
        Ok(Self {
            proxy,
            thread: Some(thread),
            closed,
            extensions,
        })
    }

    /// The instance extensions the render's device must be opened with
    /// ([`Gpu::new_for_presentation`]).
    pub fn surface_extensions(&self) -> &[&'static CStr] {
        &self.extensions
    }

    /// Makes the window's surface and swapchain on `gpu` and starts showing `feed`.
    pub fn attach(&self, gpu: &Gpu, feed: Arc<FilmFeed>) -> Result<(), PreviewError> {
        let (reply, answer) = mpsc::channel();
        self.proxy
            .send_event(Command::Attach {
                gpu: gpu.clone(),
                feed,
                reply,
            })
            .map_err(|_| PreviewError::Window("the window's thread ended".into()))?;
        answer
            .recv_timeout(WINDOW_TIMEOUT)
            .map_err(|_| PreviewError::Window("the window did not answer".into()))?
            .map_err(PreviewError::Window)
    }

    /// Whether the window was closed (the render should stop).
    pub fn closed(&self) -> bool {
        self.closed.load(Ordering::SeqCst)
    }

    /// Closes the window (after its last frame) and ends its thread.
    pub fn close(mut self) {
        self.shut_down();
    }

    fn shut_down(&mut self) {
        if let Some(thread) = self.thread.take() {
            let _ = self.proxy.send_event(Command::Close);
            let _ = thread.join();
        }
    }
}

impl Drop for Preview {
    fn drop(&mut self) {
        self.shut_down();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn small_films_are_magnified_and_large_ones_shrunk() {
        assert_eq!(window_size([64, 64]), [512, 512]);
        assert_eq!(window_size([80, 60]), [480, 360]);
        assert_eq!(window_size([512, 384]), [512, 384]);
        assert_eq!(window_size([4096, 1024]), [1280, 320]);
        assert_eq!(window_size([1, 16384]), [1, 1024]);
        assert_eq!(window_size([0, 0]), [512, 512]);
    }
}
