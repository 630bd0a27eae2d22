//! The options of `splitray render`: the scene's or a checkpoint's, with the command
//! line's on top.

use std::path::Path;

use anyhow::{anyhow, bail};
use splitray::integrator::IntegratorKind;
use splitray::render::{Checkpoint, RenderOptions, Shard};
use splitray::scene::Scene;

use super::RenderArgs;

pub(super) fn parse_shard(spec: &str) -> anyhow::Result<Shard> {
    let shard = if spec == "auto" {
        Shard::from_environment(|name| std::env::var(name).ok())
    } else {
        spec.parse()
    };
    shard.map_err(|e| anyhow!("--shard: {e}"))
}

/// The options of this render: the scene's, or the checkpoint's when resuming,
/// overridden by whatever the command line gives.
pub(super) fn render_options(
    args: &RenderArgs,
    scene: &Scene,
    resume: Option<&(Checkpoint, &Path)>,
) -> anyhow::Result<RenderOptions> {
    let mut options = match resume {
        None => RenderOptions::resolve(
            scene,
            args.width,
            args.height,
            args.spp,
            args.seed,
            args.integrator,
            args.tracer,
        )?,
        Some((checkpoint, path)) => resumed_options(args, checkpoint, path)?,
    };
    check_options_apply(args, options.integrator)?;
    if let Some(t) = args.time {
        if !t.is_finite() || t <= 0.0 {
            bail!("--time must be a positive number of seconds");
        }
        options.time_limit = Some(t);
        if args.spp.is_none() && resume.is_none() {
            options.spp = u32::MAX;
        }
    }
    if let Some(d) = args.max_depth {
        options.max_depth = d;
    }
    if let Some(r) = args.rr_depth {
        options.rr_depth = r;
    }
    if args.no_sort {
        options.sort_materials = Some(false);
        options.lvc.sort = Some(false);
    }
    if args.sort {
        options.sort_materials = Some(true);
        options.lvc.sort = Some(true);
    }
    if args.connections.is_some() {
        options.lvc.connections = args.connections;
    }
    if args.candidates.is_some() {
        options.lvc.candidates = args.candidates;
    }
    if args.resampling.is_some() {
        options.lvc.resampling = args.resampling;
    }
    if args.streams.is_some() {
        options.lvc.streams = args.streams;
    }
    if let Some(s) = args.strategy {
        options.strategy = s;
    }
    if let Some(path) = &args.reference {
        options.reference = Some(std::sync::Arc::new(splitray::film::Reference::read(
            path,
            options.width,
            options.height,
        )?));
    }
    cbpt_settings(args, &mut options.cbpt)?;
    if let Some(dir) = &args.bdpt_techniques {
        if resume.is_some() {
            bail!("--bdpt-techniques cannot be used with --resume: a checkpoint keeps the image's sums, not the technique images'");
        }
        super::check_technique_dir(dir, options.integrator)?;
        options.bdpt_techniques = true;
    }
    Ok(options)
}

/// Refuses an option that only some integrators take (as `render --help` says) given for
/// another: it would change nothing, and the user expects it to.
fn check_options_apply(args: &RenderArgs, integrator: IntegratorKind) -> anyhow::Result<()> {
    use IntegratorKind::{Bpt, Cbpt, CisLbdpt, Light, LvcBdpt, Pt};
    const DEPTH: &[IntegratorKind] = &[Pt, Bpt, Light, LvcBdpt, CisLbdpt, Cbpt];
    const SORTING: &[IntegratorKind] = &[Pt, LvcBdpt, CisLbdpt];
    const CACHE: &[IntegratorKind] = &[LvcBdpt, CisLbdpt];
    let given: [(&str, bool, &[IntegratorKind]); 14] = [
        ("--max-depth", args.max_depth.is_some(), DEPTH),
        ("--rr-depth", args.rr_depth.is_some(), DEPTH),
        ("--sort", args.sort, SORTING),
        ("--no-sort", args.no_sort, SORTING),
        ("--strategy", args.strategy.is_some(), &[Pt]),
        ("--connections", args.connections.is_some(), CACHE),
        ("--streams", args.streams.is_some(), CACHE),
        ("--candidates", args.candidates.is_some(), &[CisLbdpt]),
        ("--resampling", args.resampling.is_some(), &[CisLbdpt]),
        ("--cbpt-nc", args.cbpt_nc.is_some(), &[Cbpt]),
        ("--cbpt-nl", args.cbpt_nl.is_some(), &[Cbpt]),
        ("--cbpt-nt", args.cbpt_nt.is_some(), &[Cbpt]),
        ("--cbpt-batch", args.cbpt_batch.is_some(), &[Cbpt]),
        ("--cbpt-combine", args.cbpt_combine.is_some(), &[Cbpt]),
    ];
    for (option, given, takers) in given {
        if given && !takers.contains(&integrator) {
            let names: Vec<&str> = takers.iter().map(|k| k.name()).collect();
            bail!(
                "{option} is an option of {}, not of {integrator}",
                names.join(", ")
            );
        }
    }
    Ok(())
}

/// The checkpoint's options with the command line's on top; without --spp or --time,
/// the render goes on to the checkpoint's own target (its spp, or what is left of its
/// time).
fn resumed_options(
    args: &RenderArgs,
    checkpoint: &Checkpoint,
    path: &Path,
) -> anyhow::Result<RenderOptions> {
    let header = &checkpoint.header;
    let mut options = header
        .options
        .to_options()
        .map_err(|e| anyhow!("{}: {e}", path.display()))?;
    options.width = args.width.unwrap_or(options.width);
    options.height = args.height.unwrap_or(options.height);
    options.seed = args.seed.unwrap_or(options.seed);
    options.integrator = args.integrator.unwrap_or(options.integrator);
    options.tracer = args.tracer.unwrap_or(options.tracer);
    if let Some(spp) = args.spp {
        if spp == 0 {
            bail!("--spp must be at least 1");
        }
        let held = header.passes as u64 * header.samples_per_pass as u64;
        if header.shard.is_whole() && u64::from(spp) <= held {
            bail!(
                "{}: it holds {held} spp already, so --spp {spp} adds nothing: ask for more \
                 than {held}",
                path.display()
            );
        }
        options.spp = spp;
        options.time_limit = None;
    } else if let (None, Some(limit)) = (args.time, header.options.time_limit) {
        let left = limit - header.render_time_s;
        if left <= 0.0 {
            bail!(
                "{}: its --time {limit} s is spent ({:.1} s rendered): continue it with \
                 --time SECONDS or --spp N",
                path.display(),
                header.render_time_s
            );
        }
        options.time_limit = Some(left);
    }
    Ok(options)
}

/// `--cbpt-*` on top of the scene's or the checkpoint's CBPT settings.
fn cbpt_settings(
    args: &RenderArgs,
    settings: &mut splitray::integrator::cbpt::CbptSettings,
) -> anyhow::Result<()> {
    if let Some(n) = args.cbpt_nc {
        settings.camera_paths = n;
    }
    if let Some(n) = args.cbpt_nl {
        settings.light_paths = n;
    }
    if let Some(n) = args.cbpt_nt {
        settings.light_traced = n;
    }
    if let Some(n) = args.cbpt_batch {
        settings.batch = n;
    }
    if let Some(c) = args.cbpt_combine {
        settings.combination = c;
    }
    settings.check().map_err(|e| anyhow!(e))
}
