//! `--preview` and `--display-server`: who watches the render converge, set up before any
//! work so that a missing display or a malformed address fails at once.

use std::path::Path;
use std::sync::Arc;

use anyhow::anyhow;
#[cfg(not(x11_preview))]
use anyhow::bail;
use splitray::display::tev::{parse_address, TevStream};
use splitray::display::{FeedPublisher, FilmFeed};
use splitray::vk::{Gpu, GpuDesc};

use super::RenderArgs;

/// The longest batch of passes while a window shows the render: its title and (for
/// integrators whose film changes once per call) its image move about twice a second.
/// Shorter batches cost some throughput: each pays the integrator's per-call overhead.
const PREVIEW_BATCH_S: f64 = 0.5;
/// The same while only tev watches.
const DISPLAY_SERVER_BATCH_S: f64 = 1.0;

/// The watchers of one render.
pub(super) struct Watching {
    feed: Option<Arc<FilmFeed>>,
    #[cfg(x11_preview)]
    preview: Option<splitray::preview::Preview>,
    display_server: Option<String>,
    tev: Option<TevStream>,
    image_name: String,
}

impl Watching {
    /// Checks the address and opens the window, if asked for.
    pub(super) fn open(
        args: &RenderArgs,
        scene_name: &str,
        output: &Path,
        film: [u32; 2],
    ) -> anyhow::Result<Self> {
        #[cfg(not(x11_preview))]
        if args.preview {
            let _ = film;
            bail!(
                "--preview: this build of splitray has no preview window (it needs the \
                 `window` feature and an X11 system); --display-server HOST:PORT shows the \
                 render in tev instead"
            );
        }
        let display_server = args
            .display_server
            .as_deref()
            .map(parse_address)
            .transpose()
            .map_err(|e| anyhow!("--display-server: {e}"))?;
        let batch_s = match (args.preview, &display_server) {
            (true, _) => Some(PREVIEW_BATCH_S),
            (false, Some(_)) => Some(DISPLAY_SERVER_BATCH_S),
            (false, None) => None,
        };
        let image_name = output.file_name().map_or_else(
            || scene_name.to_string(),
            |n| n.to_string_lossy().into_owned(),
        );
        Ok(Self {
            feed: batch_s.map(|s| FilmFeed::new(Some(s))),
            #[cfg(x11_preview)]
            preview: open_preview(args, scene_name, output, film)?,
            display_server,
            tev: None,
            image_name,
        })
    }

    /// Opens the render's device: with the window system's surface extensions and
    /// VK_KHR_swapchain when a window shows the render.
    pub(super) fn open_gpu(&self, desc: &GpuDesc) -> anyhow::Result<Gpu> {
        #[cfg(x11_preview)]
        if let Some(preview) = &self.preview {
            return Ok(Gpu::new_for_presentation(
                desc,
                preview.surface_extensions(),
            )?);
        }
        Ok(Gpu::new(desc)?)
    }

    /// Makes the window's swapchain on `gpu` and starts the display-server stream.
    pub(super) fn attach(&mut self, gpu: &Gpu) -> anyhow::Result<()> {
        let Some(feed) = &self.feed else {
            return Ok(());
        };
        #[cfg(x11_preview)]
        if let Some(preview) = &self.preview {
            preview.attach(gpu, feed.clone())?;
        }
        #[cfg(not(x11_preview))]
        let _ = gpu;
        if let Some(address) = &self.display_server {
            self.tev = Some(TevStream::start(
                address.clone(),
                self.image_name.clone(),
                feed.clone(),
            )?);
        }
        Ok(())
    }

    /// What the render loop tells the watchers through.
    pub(super) fn publisher(&self) -> Option<FeedPublisher> {
        self.feed.as_ref().map(|f| f.publisher())
    }

    /// Whether the preview window was closed: the render stops, as on SIGINT.
    pub(super) fn window_closed(&self) -> bool {
        #[cfg(x11_preview)]
        if let Some(preview) = &self.preview {
            return preview.closed();
        }
        false
    }

    /// Closes the window and waits for the display server to have the finished film.
    pub(super) fn finish(self) {
        #[cfg(x11_preview)]
        if let Some(preview) = self.preview {
            preview.close();
        }
        if let Some(tev) = self.tev {
            let report = tev.finish();
            match (report.final_sent, report.connections) {
                (true, _) => splitray::outln!(
                    "display server {}: sent the finished image ({} tile updates)",
                    report.address,
                    report.updates
                ),
                (false, 0) => splitray::errln!(
                    "display server {}: never reached; nothing was shown there",
                    report.address
                ),
                (false, _) => splitray::errln!(
                    "display server {}: gone before the finished image ({} tile updates sent)",
                    report.address,
                    report.updates
                ),
            }
        }
    }
}

#[cfg(x11_preview)]
fn open_preview(
    args: &RenderArgs,
    scene_name: &str,
    output: &Path,
    film: [u32; 2],
) -> anyhow::Result<Option<splitray::preview::Preview>> {
    if !args.preview {
        return Ok(None);
    }
    let options = splitray::preview::PreviewOptions {
        name: scene_name.to_string(),
        film,
        snapshot_stem: output.with_extension(""),
    };
    Ok(Some(splitray::preview::Preview::open(options)?))
}
