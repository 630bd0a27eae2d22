//! The preview window's event handling (winit): frames about four times a second, keys,
//! resizing, and closing, which asks the render to stop.

use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::Sender;
use std::sync::Arc;
use std::time::{Duration, Instant};

use winit::application::ApplicationHandler;
use winit::dpi::PhysicalSize;
use winit::event::{ElementState, KeyEvent, WindowEvent};
use winit::event_loop::{ActiveEventLoop, ControlFlow};
use winit::keyboard::{Key, NamedKey};
use winit::window::{Window, WindowId};

use super::presenter::Presenter;
use super::PreviewOptions;
use crate::display::view::{title, ViewAction, ViewState};
use crate::display::FilmFeed;
use crate::vk::{Gpu, Presented};

/// Time between two frames. Presentation modes do not pace frames everywhere (FIFO does
/// not on Xvfb), so the window paces itself.
const FRAME_INTERVAL: Duration = Duration::from_millis(250);

/// What the render's thread asks of the window's.
pub(super) enum Command {
    /// Start showing `feed` on `gpu` (opened for presentation); the reply says whether
    /// the window can.
    Attach {
        gpu: Gpu,
        feed: Arc<FilmFeed>,
        reply: Sender<Result<(), String>>,
    },
    /// Close the window and end the event loop.
    Close,
}

/// The key that asks for `action`: arrows or +/− for exposure, 0 to reset it, A or Tab
/// for the next view, S for a snapshot, Escape or Q to close.
fn action_of(key: &KeyEvent) -> Option<ViewAction> {
    if key.state != ElementState::Pressed {
        return None;
    }
    match &key.logical_key {
        Key::Named(NamedKey::ArrowUp) => Some(ViewAction::Brighter),
        Key::Named(NamedKey::ArrowDown) => Some(ViewAction::Darker),
        Key::Named(NamedKey::Tab) => Some(ViewAction::NextView),
        Key::Named(NamedKey::Escape) => Some(ViewAction::Close),
        Key::Character(c) => match c.to_lowercase().as_str() {
            "+" | "=" => Some(ViewAction::Brighter),
            "-" | "_" => Some(ViewAction::Darker),
            "0" => Some(ViewAction::ResetExposure),
            "a" => Some(ViewAction::NextView),
            "s" => Some(ViewAction::Snapshot),
            "q" => Some(ViewAction::Close),
            _ => None,
        },
        _ => None,
    }
}

pub(super) struct App {
    options: PreviewOptions,
    /// Set once the window was closed: the render stops at its next pass boundary.
    closed: Arc<AtomicBool>,
    window: Option<Arc<Window>>,
    window_error: Option<String>,
    presenter: Option<Presenter>,
    feed: Option<Arc<FilmFeed>>,
    state: ViewState,
    next_frame: Instant,
    shown_title: String,
    /// The render's thread closed the window: its going is no request to stop.
    shutting_down: bool,
}

impl App {
    pub(super) fn new(options: PreviewOptions, closed: Arc<AtomicBool>) -> Self {
        Self {
            options,
            closed,
            window: None,
            window_error: None,
            presenter: None,
            feed: None,
            state: ViewState::default(),
            next_frame: Instant::now(),
            shown_title: String::new(),
            shutting_down: false,
        }
    }

    fn ensure_window(&mut self, event_loop: &ActiveEventLoop) {
        if self.window.is_some() || self.window_error.is_some() || self.is_closed() {
            return;
        }
        let [width, height] = super::window_size(self.options.film);
        let attributes = Window::default_attributes()
            .with_title(format!("splitray: {}", self.options.name))
            .with_inner_size(PhysicalSize::new(width, height));
        match event_loop.create_window(attributes) {
            Ok(window) => self.window = Some(Arc::new(window)),
            Err(e) => self.window_error = Some(format!("cannot open the preview window: {e}")),
        }
    }

    fn attach(&mut self, gpu: &Gpu, feed: Arc<FilmFeed>) -> Result<(), String> {
        if let Some(e) = &self.window_error {
            return Err(e.clone());
        }
        let window = self.window.clone().ok_or("the preview window was closed")?;
        let size = window.inner_size();
        let presenter = Presenter::new(gpu, window, [size.width, size.height])
            .map_err(|e| format!("cannot present to the preview window: {e}"))?;
        self.presenter = Some(presenter);
        self.feed = Some(feed);
        self.next_frame = Instant::now();
        Ok(())
    }

    fn is_closed(&self) -> bool {
        self.closed.load(Ordering::SeqCst)
    }

    /// The window goes at once; the render sees the flag at its next pass boundary and
    /// writes what it has, as on SIGINT.
    fn close_window(&mut self) {
        if !self.closed.swap(true, Ordering::SeqCst) {
            crate::errln!(
                "\npreview window closed: stopping after the passes in flight; the image is \
                 written with the samples reached"
            );
        }
        self.presenter = None;
        self.window = None;
    }

    fn frame(&mut self) {
        let closing = self.is_closed();
        let (Some(presenter), Some(feed), Some(window)) =
            (self.presenter.as_mut(), &self.feed, &self.window)
        else {
            return;
        };
        let snapshot = feed.snapshot();
        let text = title(&self.options.name, &snapshot, &self.state, closing);
        match presenter.draw(&snapshot, &self.state) {
            Ok(Some(Presented::OutOfDate)) => {
                let size = window.inner_size();
                if let Err(e) = presenter.resize([size.width, size.height]) {
                    self.fail(&e.to_string());
                }
            }
            Ok(_) => {}
            Err(e) => self.fail(&e.to_string()),
        }
        // The title follows the draw, so that it never announces a frame (its spp, its
        // view, its exposure) before that frame was handed to the window; the first
        // draw compiles the tone mapper and can take a while on a CPU device.
        if let Some(window) = &self.window {
            if text != self.shown_title {
                window.set_title(&text);
                self.shown_title = text;
            }
        }
    }

    /// A preview that cannot draw stops drawing; the render goes on.
    fn fail(&mut self, error: &str) {
        crate::errln!("preview: {error}; the window stops updating, the render goes on");
        self.presenter = None;
    }

    fn snapshot(&mut self) {
        let (Some(presenter), Some(feed)) = (self.presenter.as_mut(), &self.feed) else {
            return;
        };
        let snapshot = feed.snapshot();
        let path = PathBuf::from(format!(
            "{}.snapshot-{}spp-{}.png",
            self.options.snapshot_stem.display(),
            snapshot.spp(),
            self.state.file_tag()
        ));
        match presenter.snapshot(&snapshot, &self.state, &path) {
            Ok(written) => crate::errln!("\npreview: wrote {}", written.display()),
            Err(e) => crate::errln!("\npreview: no snapshot: {e}"),
        }
    }

    fn key(&mut self, action: ViewAction) {
        match action {
            ViewAction::Close => self.close_window(),
            ViewAction::Snapshot => self.snapshot(),
            _ => {
                if self.state.apply(action) {
                    self.frame();
                    self.next_frame = Instant::now() + FRAME_INTERVAL;
                }
            }
        }
    }
}

impl ApplicationHandler<Command> for App {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        self.ensure_window(event_loop);
    }

    fn user_event(&mut self, event_loop: &ActiveEventLoop, command: Command) {
        match command {
            Command::Attach { gpu, feed, reply } => {
                self.ensure_window(event_loop);
                let _ = reply.send(self.attach(&gpu, feed));
            }
            Command::Close => {
                self.shutting_down = true;
                self.presenter = None;
                self.window = None;
                event_loop.exit();
            }
        }
    }

    fn window_event(&mut self, _: &ActiveEventLoop, _: WindowId, event: WindowEvent) {
        match event {
            WindowEvent::CloseRequested | WindowEvent::Destroyed if !self.shutting_down => {
                self.close_window()
            }
            WindowEvent::Resized(size) => {
                if let Some(presenter) = self.presenter.as_mut() {
                    if let Err(e) = presenter.resize([size.width, size.height]) {
                        self.fail(&e.to_string());
                    }
                }
                self.next_frame = Instant::now();
            }
            WindowEvent::RedrawRequested => self.next_frame = Instant::now(),
            WindowEvent::KeyboardInput { event, .. } => {
                if let Some(action) = action_of(&event) {
                    self.key(action);
                }
            }
            _ => {}
        }
    }

    fn about_to_wait(&mut self, event_loop: &ActiveEventLoop) {
        if self.presenter.is_some() && Instant::now() >= self.next_frame {
            self.frame();
            self.next_frame = Instant::now() + FRAME_INTERVAL;
        }
        event_loop.set_control_flow(match self.presenter {
            Some(_) => ControlFlow::WaitUntil(self.next_frame),
            None => ControlFlow::Wait,
        });
    }
}
