//! [`Presenter`]: the preview's GPU side, on the window's thread. Each frame records the
//! tone-map kernel on the main stream, reading the integrator's film where it lives on
//! the GPU (in order with the passes writing it), or an upload of the latest film the
//! render loop published where the integrator keeps its film on the host, and the
//! swapchain copies its output into the window's next image.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use crate::display::tonemap::{depth_range, AovBuffers, ToneParams, Tonemapper};
use crate::display::view::ViewState;
use crate::display::{FeedInfo, FeedSnapshot};
use crate::film::FilmError;
use crate::vk::{
    self, Buffer, Gpu, MemoryKind, PixelOrder, PresentTarget, Presented, StreamKind, Surface,
    Swapchain,
};

/// The AOVs of the render being shown, uploaded once.
struct ShownFilm {
    info: Arc<FeedInfo>,
    aovs: AovBuffers,
    depth_range: (f32, f32),
    /// The latest host film (`[mean r, g, b, 1]` per pixel), where the integrator keeps
    /// its film on the host, and for the finished film.
    upload: Buffer,
    /// The feed version `upload` holds; 0 for none (it starts zeroed).
    uploaded: u64,
}

pub(super) struct Presenter {
    gpu: Gpu,
    swapchain: Swapchain,
    tonemapper: Tonemapper,
    /// The kernel's output, copied into the swapchain image.
    pixels: Option<Buffer>,
    film: Option<ShownFilm>,
}

impl Presenter {
    pub(super) fn new(
        gpu: &Gpu,
        window: Arc<dyn PresentTarget>,
        size: [u32; 2],
    ) -> vk::Result<Self> {
        let surface = Surface::new(gpu, window, StreamKind::Main)?;
        Ok(Self {
            gpu: gpu.clone(),
            swapchain: Swapchain::new(surface, size)?,
            tonemapper: Tonemapper::new(gpu)?,
            pixels: None,
            film: None,
        })
    }

    pub(super) fn resize(&mut self, size: [u32; 2]) -> vk::Result<()> {
        self.swapchain.resize(size)
    }

    /// Shows `feed`'s film as `state` asks; `Ok(None)` before the render's first pass.
    pub(super) fn draw(
        &mut self,
        feed: &FeedSnapshot,
        state: &ViewState,
    ) -> vk::Result<Option<Presented>> {
        let Some(info) = feed.info.clone() else {
            return Ok(None);
        };
        self.show(&info, feed)?;
        let extent = self.swapchain.extent();
        let bytes = extent[0] as u64 * extent[1] as u64 * 4;
        if bytes == 0 {
            return Ok(Some(Presented::NotNow));
        }
        if self.pixels.as_ref().is_none_or(|p| p.size() < bytes) {
            self.wait_for_last_frame()?;
            self.pixels = Some(self.gpu.create_buffer(
                "preview-pixels",
                bytes,
                MemoryKind::Device,
            )?);
        }
        let film = self.film.as_ref().expect("shown above");
        let params = ToneParams::new(
            [info.width, info.height],
            extent,
            state.view,
            state.exposure(),
            self.swapchain.pixel_order() == PixelOrder::Bgra8,
            film.depth_range,
        );
        let source = film_source(&info, feed, film);
        let pixels = self.pixels.as_ref().expect("made above");
        let tonemapper = &self.tonemapper;
        let aovs = &film.aovs;
        let presented = self.swapchain.present(pixels, |rec| {
            tonemapper.record(rec, &params, source, aovs, pixels)
        })?;
        Ok(Some(presented))
    }

    /// Writes what the window shows, at the film's own size, as a PNG at `path`.
    pub(super) fn snapshot(
        &mut self,
        feed: &FeedSnapshot,
        state: &ViewState,
        path: &Path,
    ) -> Result<PathBuf, String> {
        let Some(info) = feed.info.clone() else {
            return Err("the render has not started yet".into());
        };
        self.show(&info, feed).map_err(|e| e.to_string())?;
        let film = self.film.as_ref().expect("shown above");
        let size = [info.width, info.height];
        let params = ToneParams::new(
            size,
            size,
            state.view,
            state.exposure(),
            false,
            film.depth_range,
        );
        let gpu_err = |e: vk::VkError| e.to_string();
        let out = self
            .gpu
            .create_buffer(
                "preview-snapshot",
                params.out_pixels() as u64 * 4,
                MemoryKind::Readback,
            )
            .map_err(gpu_err)?;
        let mut rec = self.gpu.recorder(StreamKind::Main).map_err(gpu_err)?;
        self.tonemapper
            .record(
                &mut rec,
                &params,
                film_source(&info, feed, film),
                &film.aovs,
                &out,
            )
            .map_err(gpu_err)?;
        let done = rec.submit(&[]).map_err(gpu_err)?;
        let packed = out.read_after::<u32>(&done).map_err(gpu_err)?;
        let rgb: Vec<u8> = packed
            .iter()
            .flat_map(|p| [*p as u8, (p >> 8) as u8, (p >> 16) as u8])
            .collect();
        write_png(path, size, &rgb).map_err(|e| e.to_string())
    }

    /// Uploads the AOVs of a new film and the host film of a newer feed.
    fn show(&mut self, info: &Arc<FeedInfo>, feed: &FeedSnapshot) -> vk::Result<()> {
        if self
            .film
            .as_ref()
            .is_none_or(|f| !Arc::ptr_eq(&f.info, info))
        {
            self.wait_for_last_frame()?;
            let pixels = info.width as usize * info.height as usize;
            self.film = Some(ShownFilm {
                info: info.clone(),
                aovs: AovBuffers::upload(&self.gpu, &info.aovs)?,
                depth_range: depth_range(&info.aovs.depth),
                upload: self.gpu.zeroed::<[f32; 4]>("preview-host-film", pixels)?,
                uploaded: 0,
            });
        }
        let wanted = match (&feed.host, info.device_film.is_some() && !feed.finished) {
            (Some(host), false) => Some(host),
            _ => None,
        };
        let stale = self
            .film
            .as_ref()
            .is_some_and(|f| f.uploaded != feed.version);
        if let (Some(host), true) = (wanted, stale) {
            // The last frame may still read the upload buffer.
            self.wait_for_last_frame()?;
            let sums: Vec<[f32; 4]> = host.mean.iter().map(|m| [m[0], m[1], m[2], 1.0]).collect();
            let film = self.film.as_mut().expect("made above");
            film.upload.write(&sums)?;
            film.uploaded = feed.version;
        }
        Ok(())
    }

    fn wait_for_last_frame(&self) -> vk::Result<()> {
        match self.swapchain.last_frame() {
            Some(point) => self.gpu.wait(point),
            None => Ok(()),
        }
    }
}

/// The film buffer a frame reads: the integrator's on the GPU while it renders, else the
/// uploaded host film (the finished film is always the host one: the outputs' values).
fn film_source<'a>(info: &'a FeedInfo, feed: &FeedSnapshot, film: &'a ShownFilm) -> &'a Buffer {
    match &info.device_film {
        Some(device) if !feed.finished => &device.sums,
        _ => &film.upload,
    }
}

fn write_png(path: &Path, [width, height]: [u32; 2], rgb: &[u8]) -> Result<PathBuf, FilmError> {
    crate::film::write_atomically(path, |w| {
        let png_err = |error| FilmError::Png {
            path: path.to_path_buf(),
            error,
        };
        let mut encoder = png::Encoder::new(w, width, height);
        encoder.set_color(png::ColorType::Rgb);
        encoder.set_depth(png::BitDepth::Eight);
        encoder.set_source_srgb(png::SrgbRenderingIntent::Perceptual);
        let mut writer = encoder.write_header().map_err(png_err)?;
        writer.write_image_data(rgb).map_err(png_err)?;
        writer.finish().map_err(png_err)
    })
}
