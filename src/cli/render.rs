//! `splitray render`.

use std::path::{Path, PathBuf};

use anyhow::{bail, Context};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use splitray::film::write_outputs;
use splitray::integrator::IntegratorKind;
use splitray::render::{render, RenderOptions};
use splitray::trace::TracerKind;
use splitray::vk::{Gpu, GpuDesc, InstanceDesc};

#[derive(Debug, Args)]
pub struct RenderArgs {
    /// A built-in scene name (see `splitray scenes`), a scene .toml or an .obj mesh.
    #[arg(default_value = "cornell-box")]
    scene: String,
    /// Output EXR; the PNG preview goes beside it. Default: out/<scene>.exr.
    #[arg(short, long)]
    output: Option<PathBuf>,
    /// Film width in pixels (default: the scene's, else 512).
    #[arg(long)]
    width: Option<u32>,
    /// Film height in pixels (default: the scene's, else 512).
    #[arg(long)]
    height: Option<u32>,
    /// Samples per pixel (default: the scene's, else 1; more than 1 jitters within pixels).
    #[arg(long)]
    spp: Option<u32>,
    /// Random seed (same seed, same device → same image).
    #[arg(long)]
    seed: Option<u64>,
    /// What to compute along the rays: primary (eye-light shading), ao (ambient
    /// occlusion), shadow (one point light), reflection (one mirror bounce), path
    /// (7 diffuse bounces) or pt (physically based path tracing).
    #[arg(long)]
    integrator: Option<IntegratorKind>,
    /// Render for this many seconds instead (stops after the pass during which the time
    /// ran out; with --spp, at most that many passes).
    #[arg(long, value_name = "SECONDS")]
    time: Option<f64>,
    /// pt: maximum path depth as in Mitsuba (1 = emitters seen directly, 2 = direct
    /// light, -1 = unbounded; default: the scene's, else -1).
    #[arg(long, allow_hyphen_values = true)]
    max_depth: Option<i32>,
    /// pt: Russian roulette from this depth on (Mitsuba's default 5).
    #[arg(long, default_value_t = 5)]
    rr_depth: u32,
    /// pt: do not sort paths by material before shading (same image, other speed).
    #[arg(long)]
    no_sort: bool,
    /// pt: estimators: mis (default), nee (light sampling only) or bsdf (BSDF sampling only).
    #[arg(long, default_value = "mis")]
    strategy: splitray::integrator::pt::Strategy,
    /// How rays are cast: pdacrt (default; no acceleration structure), brute-force (the
    /// oracle), cpu-dacrt (serial CPU baseline), cpu-bvh (a BVH built and traced on every
    /// CPU core) or ray-query (driver BVH, where offered).
    #[arg(long)]
    tracer: Option<TracerKind>,
    /// Vulkan device by index or name substring (see `splitray info`); also SPLITRAY_DEVICE.
    #[arg(long)]
    device: Option<String>,
    /// Run with VK_LAYER_KHRONOS_validation; any validation message fails the command.
    #[arg(long)]
    validation: bool,
    /// Also enable synchronization validation (slow; implies --validation).
    #[arg(long)]
    sync_validation: bool,
    /// Write per-kernel GPU times, rays traced, rays/s and peak GPU memory as JSON.
    #[arg(long, value_name = "STATS.json")]
    stats: Option<PathBuf>,
    /// Print the GPU scopes as a tree with total and self times.
    #[arg(long)]
    profile: bool,
    /// A reference image (an EXR of this film size, e.g. a long render or a Mitsuba
    /// reference): the relative MSE against it is shown as the render goes and recorded
    /// in the stats.
    #[arg(long, value_name = "REF.exr")]
    reference: Option<PathBuf>,
    /// Write a timeline of the render (GPU streams, host threads, counters) as
    /// trace-event JSON for ui.perfetto.dev or chrome://tracing.
    #[arg(long, value_name = "FILE.json")]
    timeline: Option<PathBuf>,
}

/// The output path, checked before any work so a bad path fails fast.
fn output_path(args: &RenderArgs, scene_name: &str) -> anyhow::Result<PathBuf> {
    let path = match &args.output {
        Some(p) => p.clone(),
        None => {
            let stem: String = scene_name
                .chars()
                .map(|c| {
                    if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                        c
                    } else {
                        '_'
                    }
                })
                .collect();
            std::fs::create_dir_all("out").context("cannot create the folder out/")?;
            PathBuf::from("out").join(format!("{stem}.exr"))
        }
    };
    if path.extension().and_then(|e| e.to_str()) != Some("exr") {
        bail!("{}: the output must be an .exr file", path.display());
    }
    let parent = path
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    if !parent.is_dir() {
        bail!(
            "{}: the folder {} does not exist",
            path.display(),
            parent.display()
        );
    }
    Ok(path)
}

pub fn run(args: &RenderArgs) -> anyhow::Result<()> {
    let mut timeline = super::timeline::TimelineOutput::start(args.timeline.as_deref())?;
    let scene = splitray::scene::load(&args.scene)?;
    let output = output_path(args, &scene.name)?;
    let mut options = RenderOptions::resolve(
        &scene,
        args.width,
        args.height,
        args.spp,
        args.seed,
        args.integrator,
        args.tracer,
    )?;
    if let Some(t) = args.time {
        if t.is_nan() || t <= 0.0 {
            bail!("--time must be a positive number of seconds");
        }
        options.time_limit = Some(t);
        if args.spp.is_none() {
            options.spp = u32::MAX;
        }
    }
    if let Some(d) = args.max_depth {
        options.max_depth = d;
    }
    options.rr_depth = args.rr_depth;
    options.sort_materials = !args.no_sort;
    options.strategy = args.strategy;
    if let Some(path) = &args.reference {
        options.reference = Some(std::sync::Arc::new(read_reference(path, &options)?));
    }
    let gpu = Gpu::new(&GpuDesc {
        instance: InstanceDesc {
            validation: args.validation,
            sync_validation: args.sync_validation,
        },
        device: args.device.clone(),
        ..Default::default()
    })?;
    if let Some(t) = timeline.as_mut() {
        t.attach(&gpu)?;
    }

    let bar = match options.time_limit {
        // Timed: the bar runs over seconds; the message carries passes and samples/s.
        Some(t) => {
            let bar = ProgressBar::new((t * 10.0).ceil() as u64);
            bar.set_style(
                ProgressStyle::with_template("{spinner} {msg} [{bar:30}] {elapsed} eta {eta}")
                    .expect("valid progress template")
                    .progress_chars("=> "),
            );
            bar
        }
        None => {
            let bar = ProgressBar::new(options.spp as u64);
            bar.set_style(
                ProgressStyle::with_template(
                    "{spinner} {msg} [{bar:30}] {pos}/{len} spp  {per_sec}  eta {eta}",
                )
                .expect("valid progress template")
                .progress_chars("=> "),
            );
            bar
        }
    };
    let pixels = options.width as f64 * options.height as f64;
    let timed = options.time_limit.is_some();
    bar.set_message(format!(
        "{} {}x{}",
        scene.name, options.width, options.height
    ));
    let label = format!("{} {}x{}", scene.name, options.width, options.height);
    let result = render(&gpu, &scene, &options, &mut |p| {
        let rate = p.spp as f64 * pixels / p.elapsed_s.max(1e-9);
        let mse = p
            .relative_mse
            .map(|m| format!(", relMSE {m:.4e}"))
            .unwrap_or_default();
        bar.set_message(format!(
            "{label} {} spp, {:.3} Msamples/s{mse}",
            p.spp,
            rate * 1e-6
        ));
        if timed {
            bar.set_position((p.elapsed_s * 10.0) as u64);
        } else {
            bar.set_position(p.spp);
        }
    });
    bar.finish_and_clear();
    let result = result?;

    let messages = gpu.validation_messages();
    if !messages.is_empty() {
        bail!(
            "{} validation message(s) (see the log above); nothing was written",
            messages.len()
        );
    }
    let written = {
        let _span = tracing::info_span!("write outputs").entered();
        write_outputs(&output, &result.film, &result.metadata)?
    };
    let s = &result.stats;
    println!(
        "{}: {}x{} {} spp, {} + {} on {} in {:.3} s: {} rays, {:.2} Mrays/s, peak GPU memory {:.1} MiB",
        s.scene,
        s.width,
        s.height,
        s.spp,
        s.integrator,
        s.tracer,
        s.device,
        s.render_time_s,
        s.rays_traced,
        s.rays_per_second * 1e-6,
        s.peak_gpu_bytes as f64 / (1 << 20) as f64
    );
    println!(
        "wrote {} and {}",
        written.exr.display(),
        written.png.display()
    );
    if let Some(mse) = s.relative_mse {
        println!("relative MSE against the reference: {mse:.6e}");
    }
    if args.profile {
        print!("{}", s.profile.table());
    }
    if let Some(path) = &args.stats {
        let json = serde_json::to_vec_pretty(s)?;
        splitray::film::atomic::write_bytes_atomically(path, &json)
            .with_context(|| format!("cannot write {}", path.display()))?;
    }
    if let Some(t) = timeline {
        t.finish(&super::timeline::command_line())?;
    }
    Ok(())
}

/// The reference image's mean RGB, refused unless it has this render's film size.
fn read_reference(path: &Path, options: &RenderOptions) -> anyhow::Result<Vec<[f32; 3]>> {
    let (film, _) = splitray::film::read_exr(path)?;
    if (film.width(), film.height()) != (options.width, options.height) {
        bail!(
            "{}: the reference is {}x{}, the render {}x{}",
            path.display(),
            film.width(),
            film.height(),
            options.width,
            options.height
        );
    }
    Ok(film.mean_rgb_buffer())
}
