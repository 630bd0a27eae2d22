//! `splitray merge`: parts of one image (`render --shard I/N`) into one EXR, weighted by
//! their samples, with the merged standard error.

use std::path::PathBuf;

use clap::Args;
use splitray::film::ImageFiles;
use splitray::render::merge::merge_parts;

use super::paths::{check_output, refuse_clashing_paths, Role};

#[derive(Debug, Args)]
pub struct MergeArgs {
    /// The parts: EXRs written by `splitray render --shard I/N` (or by merge itself).
    #[arg(required = true, value_name = "PART.exr")]
    parts: Vec<PathBuf>,
    /// The merged EXR (mean and standard error); its PNG preview goes beside it.
    #[arg(short, long, value_name = "OUT.exr")]
    output: PathBuf,
}

pub fn run(args: &MergeArgs) -> anyhow::Result<()> {
    let output = &args.output;
    check_output(output, &["exr"], "an .exr file")?;
    refuse_clashes(args)?;
    // Created before the parts are read: an output that cannot be written fails first.
    let files = ImageFiles::create(output)?;
    let merged = merge_parts(&args.parts)?;
    let written = files.write(&merged.film, &merged.metadata)?;
    let film = &merged.film;
    let parts = match args.parts.len() {
        1 => "1 part".to_string(),
        n => format!("{n} parts"),
    };
    splitray::outln!(
        "merged {parts}: {}x{} {} spp (passes {}), {} on {}",
        film.width(),
        film.height(),
        merged.sums.spp(),
        merged.record.passes,
        merged.metadata.integrator,
        merged.metadata.device
    );
    if let Some(stderr) = &film.stderr {
        let mean_stderr = stderr.iter().flatten().map(|&v| v as f64).sum::<f64>()
            / (3 * stderr.len()).max(1) as f64;
        splitray::outln!("standard error: {mean_stderr:.4e} on average over pixels and channels");
    }
    if !merged.missing_shards.is_empty() {
        splitray::errln!(
            "warning: no part is shard {}: the image holds fewer samples than its render asked for",
            merged.missing_shards
        );
    } else {
        // Shards of renders of different lengths, say: valid, but not what one render
        // of that many samples would have made.
        let gaps = merged.record.passes.gaps();
        if !gaps.is_empty() {
            let names: Vec<String> = gaps
                .iter()
                .map(|g| format!("{}..{}", g.start, g.end))
                .collect();
            splitray::errln!(
                "warning: no part holds passes {}: the image holds fewer samples than its passes' span",
                names.join(", ")
            );
        }
    }
    splitray::outln!(
        "wrote {} and {}",
        written.exr.display(),
        written.png.display()
    );
    Ok(())
}

/// Refuses an output, or the PNG preview written beside it, that is one of the parts
/// however the two paths are written (`./p.exr`, an absolute path): merging would
/// overwrite a part it read.
fn refuse_clashes(args: &MergeArgs) -> anyhow::Result<()> {
    let png = args.output.with_extension("png");
    let outputs = [
        Role::file("the output", &args.output),
        Role::file("its PNG preview", &png),
    ];
    let parts: Vec<Role> = args
        .parts
        .iter()
        .map(|part| Role::file("a part", part))
        .collect();
    refuse_clashing_paths(&outputs, &parts)
}
