//! Animated renders: a range of frames of an [`AnimatedScene`], each the render of the
//! scene posed at the frame's time.
//!
//! One tracer and one integrator serve the whole sequence. Between two frames the scene
//! moves by [`AnimatedScene::advance`], which names the triangle ranges that changed;
//! the tracer takes them through [`Tracer::update_geometry`] (PDACRT writes them in
//! place and builds nothing; ray-query and the CPU BVH build again), the integrator
//! through [`Integrator::set_frame`] (its scene tables written in place, uploading only
//! the changed ranges), and the film is cleared. Each frame is then rendered by the
//! same pass loop as a still, so frame k is bit for bit the still render of the scene
//! posed at time k (tests/suite/animation.rs).

use std::cell::RefCell;
use std::ops::Range;
use std::path::{Path, PathBuf};
use std::rc::Rc;
use std::time::Instant;

use super::{
    integrator_on, render_prepared, start_measuring, Prepared, Progress, RenderControl,
    RenderError, RenderOptions, RenderOutput, RenderPlan,
};
use crate::film::FilmSums;
use crate::integrator::{aov, Integrator, IntegratorStats, SceneFrame};
use crate::scene::animation::frame_time;
use crate::scene::{validate, AnimatedScene, Location, Scene};
use crate::trace::{pdacrt, GpuTriangle, Query, Tracer};
use crate::vk::{self, Buffer, Gpu, TimelinePoint};

/// Frames `first..end` at `fps` frames per second: frame k shows time k / fps.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrameRange {
    pub first: u32,
    /// One past the last frame.
    pub end: u32,
    pub fps: f64,
}

/// Frames per second when none is given.
pub const DEFAULT_FPS: f64 = 24.0;

impl FrameRange {
    /// `A..B` (frames A to B − 1) or `A..=B` (frames A to B), at `fps`.
    pub fn parse(spec: &str, fps: f64) -> Result<Self, String> {
        let bad = || {
            format!("'{spec}' is not a frame range: write A..B (frames A to B-1) or A..=B (A to B)")
        };
        let (a, b, inclusive) = match spec.split_once("..=") {
            Some((a, b)) => (a, b, true),
            None => {
                let (a, b) = spec.split_once("..").ok_or_else(bad)?;
                (a, b, false)
            }
        };
        let first: u32 = a.trim().parse().map_err(|_| bad())?;
        let last: u32 = b.trim().parse().map_err(|_| bad())?;
        let end = match inclusive {
            true => last.checked_add(1).ok_or_else(|| {
                format!(
                    "frame range '{spec}': the last frame is past {}",
                    u32::MAX - 1
                )
            })?,
            false => last,
        };
        if end <= first {
            return Err(format!("frame range '{spec}' holds no frames"));
        }
        if !(fps.is_finite() && fps > 0.0) {
            return Err(format!("--fps {fps} must be a positive number"));
        }
        // Frame k shows time k / fps, an f32 of the scene's clock.
        let last_time = (end - 1) as f64 / fps;
        if !(last_time as f32).is_finite() {
            return Err(format!(
                "--fps {fps} puts frame {} at {last_time:e} s, past any time a scene can \
                 hold",
                end - 1
            ));
        }
        Ok(Self { first, end, fps })
    }

    pub fn frames(&self) -> Range<u32> {
        self.first..self.end
    }

    pub fn len(&self) -> u32 {
        self.end - self.first
    }

    pub fn is_empty(&self) -> bool {
        self.end <= self.first
    }

    /// The scene time of frame `frame`.
    pub fn time(&self, frame: u32) -> f32 {
        frame_time(frame, self.fps)
    }
}

/// The file of frame `frame` of a sequence written as `base` (`out.exr`): `out_0003.exr`,
/// the number zero-padded to 4 digits, or to as many as the range's last frame needs.
pub fn frame_path(base: &Path, frame: u32, range: &FrameRange) -> PathBuf {
    let digits = (range.end - 1).to_string().len().max(4);
    let stem = base
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let ext = base
        .extension()
        .map(|e| format!(".{}", e.to_string_lossy()))
        .unwrap_or_default();
    base.with_file_name(format!("{stem}_{frame:0digits$}{ext}"))
}

/// The frame of `range` whose image or PNG preview has `path`'s file name (beside
/// `base` or not: the caller compares folders), if any.
pub fn frame_named(base: &Path, range: &FrameRange, path: &Path) -> Option<u32> {
    let name = path.file_name()?.to_str()?;
    let stem = base.file_stem()?.to_str()?;
    let number = Path::new(name.strip_prefix(stem)?.strip_prefix('_')?)
        .file_stem()?
        .to_str()?;
    // Any spelling that parses ("+7", "007") is caught by comparing the names below.
    let frame: u32 = number.parse().ok()?;
    let image = frame_path(base, frame, range);
    let names_it = |p: &Path| p.file_name().and_then(|n| n.to_str()) == Some(name);
    let inside = (range.first..range.end).contains(&frame);
    (inside && (names_it(&image) || names_it(&image.with_extension("png")))).then_some(frame)
}

/// One finished frame.
pub struct Frame {
    pub index: u32,
    /// The scene time it shows.
    pub time: f32,
    pub output: RenderOutput,
    /// Triangles uploaded again for it (0 for the first frame).
    pub changed_triangles: usize,
}

/// What a caller does while a sequence renders.
pub struct FramesControl<'a> {
    /// Told after every batch of passes, with the frame's index.
    pub progress: &'a mut dyn FnMut(u32, &Progress),
    /// Asked before every batch, and within a long pass ([`RenderControl::abandon`]):
    /// `true` stops the sequence (the frame in progress is dropped, the frames done stay
    /// done).
    pub stop: &'a dyn Fn() -> bool,
    /// Given each finished frame, in order (to write it); an error ends the sequence.
    pub frame_done: &'a mut dyn FnMut(Frame) -> Result<(), RenderError>,
}

/// How a sequence ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FramesRun {
    /// Frames finished and handed over.
    pub frames: u32,
    /// Stopped by the caller before the last frame.
    pub stopped: bool,
}

/// Refuses what cannot render `range` of `animated`: an integrator that cannot animate,
/// and a camera that is invalid at one of the frames (keys interpolated into a camera
/// whose up is parallel to its view, say). Runs before any GPU work.
pub fn check_frames(
    animated: &AnimatedScene,
    options: &RenderOptions,
    range: &FrameRange,
) -> Result<(), RenderError> {
    if !options.integrator.animates() {
        return Err(RenderError::Options(format!(
            "the {} integrator cannot render animated scenes yet (--frames)",
            options.integrator
        )));
    }
    let at = Location::file(format!("scene '{}'", animated.scene.name));
    for k in range.frames() {
        let t = range.time(k);
        validate::validate_camera(&animated.camera_at(t), &at)
            .map_err(|e| RenderError::Options(format!("frame {k} (t = {t} s): {e}")))?;
    }
    Ok(())
}

/// Renders frames `range` of `animated`, handing each to `control.frame_done` as it is
/// finished.
pub fn render_frames(
    gpu: &Gpu,
    animated: &AnimatedScene,
    options: &RenderOptions,
    range: &FrameRange,
    control: FramesControl<'_>,
) -> Result<FramesRun, RenderError> {
    check_frames(animated, options, range)?;
    let mut sequence = Sequence::start(gpu, animated, options, range)?;
    let mut run = FramesRun {
        frames: 0,
        stopped: false,
    };
    // A frame's counts start where the previous frame's ended (the first frame's at
    // zero), so that they hold what moving the integrator to the frame cost (the light
    // vertex cache's prepass on the posed scene) as a still render's hold what making
    // the integrator cost: frame k counts what the still render at time k counts.
    let mut stats_before = IntegratorStats::default();
    for k in range.frames() {
        if (control.stop)() {
            run.stopped = true;
            break;
        }
        let _span = tracing::info_span!("frame", index = k).entered();
        let start = start_measuring(gpu)?;
        let mut changed_triangles = 0;
        if k != range.first {
            changed_triangles = sequence.advance(animated, options, k, range.time(k))?;
        }
        let mut output = sequence.render(
            gpu,
            options,
            start,
            stats_before.clone(),
            RenderControl {
                progress: &mut |p| (control.progress)(k, p),
                stop: control.stop,
                // The frame in progress is dropped anyway.
                abandon: control.stop,
            },
        )?;
        stats_before = sequence.integrator.stats();
        if output.stats.stopped_early {
            run.stopped = true;
            break;
        }
        output.metadata.extra.push(("frame".into(), k.to_string()));
        output
            .metadata
            .extra
            .push(("time".into(), sequence.time.to_string()));
        (control.frame_done)(Frame {
            index: k,
            time: sequence.time,
            output,
            changed_triangles,
        })?;
        run.frames += 1;
    }
    Ok(run)
}

/// A sequence as it renders: the scene posed at the current frame, with the one tracer
/// and integrator that follow it from frame to frame. The fields drop in the order
/// declared: the AOVs' triangles, then the integrator, then the tracer it shares.
struct Sequence {
    /// The triangles the AOVs are rendered from.
    aov_triangles: Buffer,
    integrator: Box<dyn Integrator>,
    tracer: Rc<RefCell<Shared>>,
    triangles: Vec<GpuTriangle>,
    scene: Scene,
    /// The scene time the scene is posed at.
    time: f32,
}

impl Sequence {
    /// The scene posed at the range's first frame, and the tracer and integrator on it.
    fn start(
        gpu: &Gpu,
        animated: &AnimatedScene,
        options: &RenderOptions,
        range: &FrameRange,
    ) -> Result<Self, RenderError> {
        let time = range.time(range.first);
        let scene = animated.pose(time);
        // Every frame has the first frame's triangle count and film.
        super::device_fit::check(gpu, &scene, options)?;
        let triangles = scene.gpu_triangles();
        let tracer = Rc::new(RefCell::new(Shared {
            tracer: options.tracer.create(gpu, &triangles)?,
            holds: range.first,
            current: range.first,
        }));
        let integrator = integrator_on(
            gpu,
            &scene,
            options,
            &triangles,
            Box::new(SharedTracer(tracer.clone())),
        )?;
        super::warn_if_spp_rounds_up(options, integrator.as_ref());
        let aov_triangles = gpu.upload("aov-triangles", &triangles)?;
        Ok(Self {
            aov_triangles,
            integrator,
            tracer,
            triangles,
            scene,
            time,
        })
    }

    /// Poses the scene at frame `frame`, time `time`, and moves the tracer, the
    /// integrator and the AOVs' triangles with it; returns how many triangles moved.
    fn advance(
        &mut self,
        animated: &AnimatedScene,
        options: &RenderOptions,
        frame: u32,
        time: f32,
    ) -> Result<usize, RenderError> {
        let changed = animated.advance(&mut self.scene, self.time, time);
        self.time = time;
        let changed_triangles = move_triangles(&mut self.triangles, &self.scene, &changed);
        {
            // Where nothing moved, the tracer already holds this frame's geometry.
            let mut shared = self.tracer.borrow_mut();
            shared.current = frame;
            if changed_triangles == 0 {
                shared.holds = frame;
            }
        }
        next_frame(
            self.integrator.as_mut(),
            &self.scene,
            &self.triangles,
            &changed,
            options,
        )?;
        // The CPU integrators trace without it: the AOVs still need it moved.
        SharedTracer(self.tracer.clone()).update_geometry(&self.triangles, &changed)?;
        crate::integrator::frame::write_ranges(&self.aov_triangles, &self.triangles, &changed, 1)?;
        Ok(changed_triangles)
    }

    /// Renders the frame the scene is posed at: its AOVs, then its passes.
    fn render(
        &mut self,
        gpu: &Gpu,
        options: &RenderOptions,
        start: Instant,
        stats_before: IntegratorStats,
        control: RenderControl<'_>,
    ) -> Result<RenderOutput, RenderError> {
        let camera = self.scene.camera.frame(options.width, options.height);
        let aovs = aov::render_aovs(
            gpu,
            &mut SharedTracer(self.tracer.clone()),
            &self.aov_triangles,
            &camera,
        )?;
        render_prepared(
            gpu,
            &self.scene,
            options,
            Prepared {
                integrator: self.integrator.as_mut(),
                aovs,
                start,
                stats_before,
            },
            RenderPlan::default(),
            control,
        )
    }
}

/// Moves the integrator to the scene as posed now, and clears its film.
fn next_frame(
    integrator: &mut dyn Integrator,
    scene: &Scene,
    triangles: &[GpuTriangle],
    changed: &[Range<usize>],
    options: &RenderOptions,
) -> Result<(), RenderError> {
    integrator.set_frame(&SceneFrame {
        scene,
        triangles,
        changed,
        camera: scene.camera.frame(options.width, options.height),
    })?;
    // Every integrator takes a film without second moments as zeros for them too.
    integrator.restore(&FilmSums::new(
        options.width,
        options.height,
        integrator.samples_per_pass(),
        false,
    ))?;
    Ok(())
}

/// Rewrites the `changed` ranges of `triangles` from `scene`'s; returns how many.
pub fn move_triangles(
    triangles: &mut [GpuTriangle],
    scene: &Scene,
    changed: &[Range<usize>],
) -> usize {
    for r in changed {
        for (g, t) in triangles[r.clone()]
            .iter_mut()
            .zip(&scene.triangles[r.clone()])
        {
            *g = GpuTriangle::new(t.p);
        }
    }
    changed.iter().map(|r| r.len()).sum()
}

/// The sequence's one tracer, and which frame's geometry it holds.
struct Shared {
    tracer: Box<dyn Tracer>,
    holds: u32,
    /// The frame the sequence is at.
    current: u32,
}

/// A handle on the one tracer, for the integrator and for the AOVs: the first handle
/// that moves it to the current frame moves it, later ones find it there.
struct SharedTracer(Rc<RefCell<Shared>>);

impl Tracer for SharedTracer {
    fn name(&self) -> &'static str {
        self.0.borrow().tracer.name()
    }
    fn set_geometry(&mut self, triangles: &[GpuTriangle]) -> vk::Result<()> {
        let mut shared = self.0.borrow_mut();
        shared.tracer.set_geometry(triangles)?;
        shared.holds = shared.current;
        Ok(())
    }
    fn update_geometry(
        &mut self,
        triangles: &[GpuTriangle],
        changed: &[Range<usize>],
    ) -> vk::Result<()> {
        let mut shared = self.0.borrow_mut();
        let moved = changed.iter().any(|r| !r.is_empty());
        if shared.holds != shared.current && moved {
            shared.tracer.update_geometry(triangles, changed)?;
        }
        shared.holds = shared.current;
        Ok(())
    }
    fn trace(
        &mut self,
        rays: &Buffer,
        hits: &Buffer,
        ray_count: u32,
        query: Query,
        after: &[&TimelinePoint],
    ) -> vk::Result<TimelinePoint> {
        let mut shared = self.0.borrow_mut();
        // An integrator that traces in `set_frame` (the light vertex cache's prepass)
        // must move the geometry first: rays of frame k against frame j's triangles
        // would render a pose that never was.
        if shared.holds != shared.current {
            return Err(vk::VkError::Usage(format!(
                "frame {}: traced against frame {}'s geometry (set_frame traced before moving the tracer)",
                shared.current, shared.holds
            )));
        }
        shared.tracer.trace(rays, hits, ray_count, query, after)
    }
    fn level_stats(&self) -> Option<&pdacrt::TraceStats> {
        // The statistics live behind the shared borrow; the sequence does not report them.
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ranges_parse() {
        let r = FrameRange::parse("3..7", 24.0).unwrap();
        assert_eq!((r.first, r.end, r.len()), (3, 7, 4));
        let r = FrameRange::parse("0..=9", 30.0).unwrap();
        assert_eq!((r.first, r.end), (0, 10));
        assert_eq!(r.time(15), 0.5);
        for bad in ["", "3", "a..b", "5..5", "5..2", "-1..3", "0..=4294967295"] {
            assert!(FrameRange::parse(bad, 24.0).is_err(), "{bad}");
        }
        assert!(FrameRange::parse("0..2", 0.0).is_err());
        assert!(FrameRange::parse("0..2", f64::NAN).is_err());
        let past = FrameRange::parse("4294967294..=4294967295", 24.0).unwrap_err();
        assert!(past.contains("the last frame is past 4294967294"), "{past}");
        // Frame 1 at 1e-40 fps would show time 1e40 s, which no f32 holds.
        let never = FrameRange::parse("0..2", 1e-40).unwrap_err();
        assert!(never.contains("past any time a scene can hold"), "{never}");
        assert!(FrameRange::parse("0..1", 1e-40).is_ok());
    }

    #[test]
    fn frame_paths_are_numbered_beside_the_base() {
        let r = FrameRange::parse("0..12", 24.0).unwrap();
        assert_eq!(
            frame_path(Path::new("out/shot.exr"), 3, &r),
            PathBuf::from("out/shot_0003.exr")
        );
        let r = FrameRange::parse("0..=123456", 24.0).unwrap();
        assert_eq!(
            frame_path(Path::new("a.exr"), 42, &r),
            PathBuf::from("a_000042.exr")
        );
    }

    #[test]
    fn the_frame_a_file_name_belongs_to_is_found() {
        let r = FrameRange::parse("3..12", 24.0).unwrap();
        let base = Path::new("out/shot.exr");
        let named = |p: &str| frame_named(base, &r, Path::new(p));
        assert_eq!(named("out/shot_0007.exr"), Some(7));
        assert_eq!(named("elsewhere/shot_0011.png"), Some(11));
        assert_eq!(named("shot_0003.exr"), Some(3));
        for other in [
            "out/shot_0012.exr",
            "out/shot_0002.png",
            "out/shot_007.exr",
            "out/shot_00007.exr",
            "out/shot_0007.json",
            "out/shot_+007.exr",
            "out/shot.exr",
            "out/shot_.exr",
            "out/shots_0007.exr",
            "out/stats.json",
        ] {
            assert_eq!(named(other), None, "{other}");
        }
    }
}
