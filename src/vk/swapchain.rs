//! Presentation to a window: its surface and a swapchain on the device's own queue, so that
//! an image a compute pass wrote goes on screen without a round trip through the host.
//!
//! A frame is: acquire an image (waiting on a fence, so that no submission ever waits for
//! the presentation engine and stalls the stream behind it), record the caller's pass
//! that writes packed 8-bit pixels into a buffer, copy that buffer into the image, submit
//! on the stream (in order with everything else on it) signalling the image's "rendered"
//! semaphore, and present on the stream's queue waiting for it. The surface keeps its
//! window alive, and the swapchain waits for its last frame before it is rebuilt or
//! destroyed.

use std::ffi::{c_char, CStr};
use std::sync::Arc;

use ash::{khr, vk};
use raw_window_handle::{HasDisplayHandle, HasWindowHandle};

use super::buffer::Buffer;
use super::command::Recorder;
use super::device::Gpu;
use super::error::{CallContext, Result, VkError};
use super::stream::{StreamKind, TimelinePoint};

/// A window a surface can be made for (winit's `Window` is one).
pub trait PresentTarget: HasWindowHandle + HasDisplayHandle + Send + Sync {}

impl<T: HasWindowHandle + HasDisplayHandle + Send + Sync> PresentTarget for T {}

/// The instance extensions that presenting to windows of `display` needs:
/// VK_KHR_surface and the window system's own (VK_KHR_xlib_surface on X11 …).
pub fn surface_extensions(display: &dyn HasDisplayHandle) -> Result<Vec<&'static CStr>> {
    let handle = display
        .display_handle()
        .map_err(|e| VkError::Usage(format!("no window-system display: {e}")))?;
    let names: &'static [*const c_char] =
        ash_window::enumerate_required_extensions(handle.as_raw())
            .call("enumerate_required_extensions")?;
    Ok(names
        .iter()
        // SAFETY: ash-window returns pointers to ash's static, NUL-terminated extension
        // names.
        .map(|&p| unsafe { CStr::from_ptr(p) })
        .collect())
}

/// A window's Vulkan surface, usable from one stream's queue.
pub struct Surface {
    gpu: Gpu,
    loader: khr::surface::Instance,
    raw: vk::SurfaceKHR,
    stream: StreamKind,
    /// The surface must not outlive its window.
    _window: Arc<dyn PresentTarget>,
}

impl Surface {
    /// A surface for `window`, presented to from `stream`'s queue. The device must have
    /// been opened with [`Gpu::new_for_presentation`], and that queue must be able to
    /// present to the window (an error says so otherwise).
    pub fn new(gpu: &Gpu, window: Arc<dyn PresentTarget>, stream: StreamKind) -> Result<Self> {
        if !gpu.presents() {
            return Err(VkError::Usage(
                "the device was not opened for presentation (Gpu::new_for_presentation)".into(),
            ));
        }
        let handle_error = |e| VkError::Usage(format!("the window has no handle: {e}"));
        let display = window.display_handle().map_err(handle_error)?.as_raw();
        let window_handle = window.window_handle().map_err(handle_error)?.as_raw();
        let instance = &gpu.0.instance;
        // SAFETY: the instance was created with the display's surface extensions; the
        // window and its display connection live as long as `_window`, which the
        // surface holds until it is destroyed in Drop, before the instance (the surface
        // holds a Gpu, which holds the instance).
        let raw = unsafe {
            ash_window::create_surface(&instance.entry, &instance.raw, display, window_handle, None)
        }
        .call("vkCreate*SurfaceKHR")?;
        let surface = Self {
            gpu: gpu.clone(),
            loader: khr::surface::Instance::new(&instance.entry, &instance.raw),
            raw,
            stream,
            _window: window,
        };
        let family = gpu.stream(stream).family;
        // SAFETY: the physical device and the surface belong to this instance.
        let supported = unsafe {
            surface
                .loader
                .get_physical_device_surface_support(gpu.0.info.raw, family, raw)
        }
        .call("vkGetPhysicalDeviceSurfaceSupportKHR")?;
        if !supported {
            return Err(VkError::MissingFeature {
                device: gpu.0.info.name.clone(),
                what: format!(
                    "presentation to this window from queue family {family} (its {} stream)",
                    stream.name()
                ),
            });
        }
        Ok(surface)
    }
}

impl Drop for Surface {
    fn drop(&mut self) {
        // SAFETY: the swapchain made from this surface (if any) was destroyed first: a
        // Swapchain owns its Surface and drops it after its own teardown.
        unsafe { self.loader.destroy_surface(self.raw, None) };
    }
}

/// The byte order of a swapchain's 8-bit pixels, as a packed little-endian `u32`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PixelOrder {
    /// B8G8R8A8: blue in the low byte.
    Bgra8,
    /// R8G8B8A8: red in the low byte.
    Rgba8,
}

/// What became of a frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Presented {
    /// On screen.
    Shown,
    /// The window changed (resized …): rebuild with [`Swapchain::resize`] and draw again.
    OutOfDate,
    /// No image now (the window is minimised, or the presentation engine kept every
    /// image for longer than a frame may wait): try again at the next frame.
    NotNow,
}

/// The swapchain's per-image state and the handles that live with it.
struct Chain {
    raw: vk::SwapchainKHR,
    images: Vec<vk::Image>,
    /// Per image: signalled by the frame's submission, waited for by its presentation.
    /// An image is acquired again only after its presentation ended, so its semaphore
    /// is free again by then.
    rendered: Vec<vk::Semaphore>,
}

/// A swapchain for one [`Surface`], FIFO presentation, images written by copies.
pub struct Swapchain {
    loader: khr::swapchain::Device,
    chain: Option<Chain>,
    acquired: vk::Fence,
    format: vk::Format,
    order: PixelOrder,
    extent: [u32; 2],
    /// The last frame's submission (waited for before the chain is rebuilt or destroyed).
    last: Option<TimelinePoint>,
    surface: Surface,
}

/// How long acquiring an image may wait before the frame is skipped.
const ACQUIRE_TIMEOUT_NS: u64 = 250_000_000;

impl Swapchain {
    /// A swapchain of about `size` pixels (the surface's own extent where it has one).
    pub fn new(surface: Surface, size: [u32; 2]) -> Result<Self> {
        let gpu = surface.gpu.clone();
        // SAFETY: valid physical device and surface of this instance.
        let formats = unsafe {
            surface
                .loader
                .get_physical_device_surface_formats(gpu.0.info.raw, surface.raw)
        }
        .call("vkGetPhysicalDeviceSurfaceFormatsKHR")?;
        let (format, order) = choose_format(&formats).ok_or_else(|| VkError::MissingFeature {
            device: gpu.0.info.name.clone(),
            what: "an 8-bit BGRA or RGBA sRGB-colour-space surface format for the window".into(),
        })?;
        let info = vk::FenceCreateInfo::default();
        // SAFETY: valid device.
        let acquired = unsafe { gpu.0.raw.create_fence(&info, None) }.call("vkCreateFence")?;
        let mut swapchain = Self {
            loader: khr::swapchain::Device::new(&gpu.0.instance.raw, &gpu.0.raw),
            chain: None,
            acquired,
            format,
            order,
            extent: [0, 0],
            last: None,
            surface,
        };
        swapchain.resize(size)?;
        Ok(swapchain)
    }

    /// Width and height of the images in pixels ([0, 0] while the window is minimised).
    pub fn extent(&self) -> [u32; 2] {
        self.extent
    }

    pub fn pixel_order(&self) -> PixelOrder {
        self.order
    }

    /// The last frame's submission: wait for it before changing what frames read.
    pub fn last_frame(&self) -> Option<&TimelinePoint> {
        self.last.as_ref()
    }

    /// The stream frames are submitted to.
    pub fn stream(&self) -> StreamKind {
        self.surface.stream
    }

    fn gpu(&self) -> &Gpu {
        &self.surface.gpu
    }

    /// Rebuilds the images for a window of `size` pixels.
    pub fn resize(&mut self, size: [u32; 2]) -> Result<()> {
        let caps = self.surface_capabilities()?;
        let extent = image_extent(&caps, size);
        self.retire()?;
        let old = self.chain.take();
        self.extent = [0, 0];
        if extent.width == 0 || extent.height == 0 {
            self.destroy_chain(old);
            return Ok(());
        }
        let raw = self.create_swapchain(&caps, extent, old)?;
        self.chain = Some(self.new_chain(raw)?);
        self.extent = [extent.width, extent.height];
        Ok(())
    }

    /// The surface's capabilities, or an error where its images cannot be copied into.
    fn surface_capabilities(&self) -> Result<vk::SurfaceCapabilitiesKHR> {
        let gpu = self.gpu();
        // SAFETY: valid physical device and surface.
        let caps = unsafe {
            self.surface
                .loader
                .get_physical_device_surface_capabilities(gpu.0.info.raw, self.surface.raw)
        }
        .call("vkGetPhysicalDeviceSurfaceCapabilitiesKHR")?;
        if !caps
            .supported_usage_flags
            .contains(vk::ImageUsageFlags::TRANSFER_DST)
        {
            return Err(VkError::MissingFeature {
                device: gpu.0.info.name.clone(),
                what: "swapchain images that copies can write (TRANSFER_DST)".into(),
            });
        }
        Ok(caps)
    }

    /// Creates the swapchain of `extent` images, retiring `old` (whose frames
    /// [`Swapchain::retire`] waited for) and destroying it whether or not creation
    /// succeeds.
    fn create_swapchain(
        &self,
        caps: &vk::SurfaceCapabilitiesKHR,
        extent: vk::Extent2D,
        old: Option<Chain>,
    ) -> Result<vk::SwapchainKHR> {
        let image_count = match caps.max_image_count {
            0 => caps.min_image_count + 1,
            max => (caps.min_image_count + 1).min(max),
        };
        let info = vk::SwapchainCreateInfoKHR::default()
            .surface(self.surface.raw)
            .min_image_count(image_count)
            .image_format(self.format)
            .image_color_space(vk::ColorSpaceKHR::SRGB_NONLINEAR)
            .image_extent(extent)
            .image_array_layers(1)
            .image_usage(vk::ImageUsageFlags::TRANSFER_DST)
            .image_sharing_mode(vk::SharingMode::EXCLUSIVE)
            .pre_transform(caps.current_transform)
            .composite_alpha(composite_alpha(caps))
            // FIFO is the one mode every device offers; frames are paced by the caller.
            .present_mode(vk::PresentModeKHR::FIFO)
            .clipped(true)
            .old_swapchain(old.as_ref().map_or(vk::SwapchainKHR::null(), |c| c.raw));
        // SAFETY: valid device and surface; the old swapchain (if any) is retired here
        // and destroyed below once nothing uses it (retire() waited for its frames).
        let created = unsafe { self.loader.create_swapchain(&info, None) };
        self.destroy_chain(old);
        created.call("vkCreateSwapchainKHR")
    }

    /// The images of the swapchain `raw`, just created, named, with their "rendered"
    /// semaphores. Destroys `raw` on error.
    fn new_chain(&self, raw: vk::SwapchainKHR) -> Result<Chain> {
        let gpu = self.gpu();
        // SAFETY: raw was just created.
        let images = match unsafe { self.loader.get_swapchain_images(raw) } {
            Ok(images) => images,
            Err(e) => {
                // SAFETY: unused swapchain.
                unsafe { self.loader.destroy_swapchain(raw, None) };
                return Err(VkError::Call {
                    call: "vkGetSwapchainImagesKHR",
                    result: e,
                });
            }
        };
        let mut chain = Chain {
            raw,
            images,
            rendered: Vec::new(),
        };
        for _ in 0..chain.images.len() {
            // SAFETY: valid device.
            match unsafe {
                gpu.0
                    .raw
                    .create_semaphore(&vk::SemaphoreCreateInfo::default(), None)
            } {
                Ok(s) => chain.rendered.push(s),
                Err(e) => {
                    self.destroy_chain(Some(chain));
                    return Err(VkError::Call {
                        call: "vkCreateSemaphore",
                        result: e,
                    });
                }
            }
        }
        for (i, image) in chain.images.iter().enumerate() {
            gpu.set_object_name(*image, &format!("swapchain-image-{i}"));
        }
        Ok(chain)
    }

    /// Presents one frame: `draw` records work on the swapchain's stream that leaves
    /// `extent[0] × extent[1]` packed pixels ([`Swapchain::pixel_order`], row 0 at the
    /// top) at the start of `pixels`; they are copied into the next image and presented.
    pub fn present(
        &mut self,
        pixels: &Buffer,
        draw: impl FnOnce(&mut Recorder) -> Result<()>,
    ) -> Result<Presented> {
        let [width, height] = self.extent;
        let Some(chain) = &self.chain else {
            return Ok(Presented::NotNow);
        };
        let chain_raw = chain.raw;
        let needed = width as u64 * height as u64 * 4;
        if pixels.size() < needed {
            return Err(VkError::Usage(format!(
                "'{}' holds {} bytes, a {width}x{height} frame needs {needed}",
                pixels.name(),
                pixels.size()
            )));
        }
        let gpu = self.surface.gpu.clone();
        let device = &gpu.0.raw;
        // SAFETY: valid swapchain; the fence is unsignalled (reset after every wait).
        let acquired = unsafe {
            self.loader.acquire_next_image(
                chain_raw,
                ACQUIRE_TIMEOUT_NS,
                vk::Semaphore::null(),
                self.acquired,
            )
        };
        let index = match acquired {
            Ok((index, _suboptimal)) => index as usize,
            Err(vk::Result::ERROR_OUT_OF_DATE_KHR) => return Ok(Presented::OutOfDate),
            Err(vk::Result::TIMEOUT | vk::Result::NOT_READY) => return Ok(Presented::NotNow),
            Err(result) => {
                return Err(VkError::Call {
                    call: "vkAcquireNextImageKHR",
                    result,
                })
            }
        };
        // SAFETY: the fence belongs to this device and was handed to the acquisition.
        unsafe {
            device
                .wait_for_fences(&[self.acquired], true, u64::MAX)
                .call("vkWaitForFences")?;
            device
                .reset_fences(&[self.acquired])
                .call("vkResetFences")?;
        }
        let image = chain.images[index];
        let rendered = chain.rendered[index];
        let mut rec = gpu.recorder(self.surface.stream)?;
        draw(&mut rec)?;
        rec.barrier();
        record_copy_to_image(&rec, pixels, image, width, height);
        let point = rec.submit_signalling(&[], Some(rendered))?;
        self.last = Some(point);

        let waits = [rendered];
        let swapchains = [chain_raw];
        let indices = [index as u32];
        let info = vk::PresentInfoKHR::default()
            .wait_semaphores(&waits)
            .swapchains(&swapchains)
            .image_indices(&indices);
        let presented = {
            let queue = gpu.0.queues[gpu.stream(self.surface.stream).queue]
                .lock()
                .unwrap();
            // SAFETY: the queue is externally synchronised by its mutex; the image was
            // acquired above and its copy's submission signals `rendered`.
            unsafe { self.loader.queue_present(*queue, &info) }
        };
        match presented {
            Ok(false) => Ok(Presented::Shown),
            Ok(true) | Err(vk::Result::ERROR_OUT_OF_DATE_KHR) => Ok(Presented::OutOfDate),
            Err(result) => Err(VkError::Call {
                call: "vkQueuePresentKHR",
                result,
            }),
        }
    }

    /// Waits until nothing uses the current images: the last frame's submission and its
    /// presentation's semaphore wait (a queue wait: presentation has no timeline value).
    fn retire(&mut self) -> Result<()> {
        let gpu = self.surface.gpu.clone();
        if let Some(point) = self.last.take() {
            gpu.wait(&point)?;
        }
        if self.chain.is_some() {
            let queue = gpu.0.queues[gpu.stream(self.surface.stream).queue]
                .lock()
                .unwrap();
            // SAFETY: the queue is externally synchronised by its mutex.
            unsafe { gpu.0.raw.queue_wait_idle(*queue) }.call("vkQueueWaitIdle")?;
        }
        Ok(())
    }

    fn destroy_chain(&self, chain: Option<Chain>) {
        let Some(chain) = chain else { return };
        // SAFETY: retire() waited until neither submissions nor presentation use them.
        unsafe {
            for s in chain.rendered {
                self.surface.gpu.0.raw.destroy_semaphore(s, None);
            }
            self.loader.destroy_swapchain(chain.raw, None);
        }
    }
}

impl Drop for Swapchain {
    fn drop(&mut self) {
        if let Err(e) = self.retire() {
            log::warn!("waiting for the last frame before closing the window: {e}");
        }
        let chain = self.chain.take();
        self.destroy_chain(chain);
        // SAFETY: the fence is unsignalled and no acquisition is pending.
        unsafe { self.surface.gpu.0.raw.destroy_fence(self.acquired, None) };
    }
}

/// An 8-bit format in the sRGB colour space, preferring UNORM: copies write the bytes
/// as they are, so UNORM and SRGB formats show the same (already encoded) values.
fn choose_format(formats: &[vk::SurfaceFormatKHR]) -> Option<(vk::Format, PixelOrder)> {
    let preferred = [
        (vk::Format::B8G8R8A8_UNORM, PixelOrder::Bgra8),
        (vk::Format::R8G8B8A8_UNORM, PixelOrder::Rgba8),
        (vk::Format::B8G8R8A8_SRGB, PixelOrder::Bgra8),
        (vk::Format::R8G8B8A8_SRGB, PixelOrder::Rgba8),
    ];
    preferred.into_iter().find(|(format, _)| {
        formats
            .iter()
            .any(|f| f.format == *format && f.color_space == vk::ColorSpaceKHR::SRGB_NONLINEAR)
    })
}

/// The images' extent: the surface's own, or `size` within the surface's limits where
/// the window takes the swapchain's.
fn image_extent(caps: &vk::SurfaceCapabilitiesKHR, size: [u32; 2]) -> vk::Extent2D {
    if caps.current_extent.width != u32::MAX {
        caps.current_extent
    } else {
        vk::Extent2D {
            width: size[0].clamp(caps.min_image_extent.width, caps.max_image_extent.width),
            height: size[1].clamp(caps.min_image_extent.height, caps.max_image_extent.height),
        }
    }
}

/// The first composite-alpha mode the surface supports, opaque preferred.
fn composite_alpha(caps: &vk::SurfaceCapabilitiesKHR) -> vk::CompositeAlphaFlagsKHR {
    [
        vk::CompositeAlphaFlagsKHR::OPAQUE,
        vk::CompositeAlphaFlagsKHR::INHERIT,
        vk::CompositeAlphaFlagsKHR::PRE_MULTIPLIED,
        vk::CompositeAlphaFlagsKHR::POST_MULTIPLIED,
    ]
    .into_iter()
    .find(|a| caps.supported_composite_alpha.contains(*a))
    .unwrap_or(vk::CompositeAlphaFlagsKHR::OPAQUE)
}

/// A layout change of a whole colour image, between the given (stages, accesses).
fn layout_change(
    image: vk::Image,
    (src_stage, src_access): (vk::PipelineStageFlags2, vk::AccessFlags2),
    (dst_stage, dst_access): (vk::PipelineStageFlags2, vk::AccessFlags2),
    old: vk::ImageLayout,
    new: vk::ImageLayout,
) -> vk::ImageMemoryBarrier2<'static> {
    vk::ImageMemoryBarrier2::default()
        .src_stage_mask(src_stage)
        .src_access_mask(src_access)
        .dst_stage_mask(dst_stage)
        .dst_access_mask(dst_access)
        .old_layout(old)
        .new_layout(new)
        .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
        .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
        .image(image)
        .subresource_range(
            vk::ImageSubresourceRange::default()
                .aspect_mask(vk::ImageAspectFlags::COLOR)
                .level_count(1)
                .layer_count(1),
        )
}

/// Records: layout to TRANSFER_DST (contents discarded), the buffer-to-image copy, and
/// the layout for presentation.
fn record_copy_to_image(
    rec: &Recorder,
    pixels: &Buffer,
    image: vk::Image,
    width: u32,
    height: u32,
) {
    // The copy overwrites every pixel: whatever the image held is discarded.
    let to_transfer = layout_change(
        image,
        (vk::PipelineStageFlags2::NONE, vk::AccessFlags2::NONE),
        (
            vk::PipelineStageFlags2::ALL_TRANSFER,
            vk::AccessFlags2::TRANSFER_WRITE,
        ),
        vk::ImageLayout::UNDEFINED,
        vk::ImageLayout::TRANSFER_DST_OPTIMAL,
    );
    // Presentation waits on the submission's semaphore, which covers all its work.
    let to_present = layout_change(
        image,
        (
            vk::PipelineStageFlags2::ALL_TRANSFER,
            vk::AccessFlags2::TRANSFER_WRITE,
        ),
        (vk::PipelineStageFlags2::NONE, vk::AccessFlags2::NONE),
        vk::ImageLayout::TRANSFER_DST_OPTIMAL,
        vk::ImageLayout::PRESENT_SRC_KHR,
    );
    let region = vk::BufferImageCopy::default()
        .image_subresource(
            vk::ImageSubresourceLayers::default()
                .aspect_mask(vk::ImageAspectFlags::COLOR)
                .layer_count(1),
        )
        .image_extent(vk::Extent3D {
            width,
            height,
            depth: 1,
        });
    let device = &rec.gpu().0.raw;
    let cmd = rec.raw_cmd();
    // SAFETY: recording; the image is an acquired swapchain image of this device and the
    // buffer holds width × height 4-byte pixels (checked by the caller).
    unsafe {
        let first = [to_transfer];
        device.cmd_pipeline_barrier2(
            cmd,
            &vk::DependencyInfo::default().image_memory_barriers(&first),
        );
        device.cmd_copy_buffer_to_image(
            cmd,
            pixels.raw,
            image,
            vk::ImageLayout::TRANSFER_DST_OPTIMAL,
            &[region],
        );
        let last = [to_present];
        device.cmd_pipeline_barrier2(
            cmd,
            &vk::DependencyInfo::default().image_memory_barriers(&last),
        );
    }
}
