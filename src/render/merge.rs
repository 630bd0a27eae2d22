//! Merging parts of one image — shards, or images merged before — into one, weighted by
//! their passes, with the merged standard error.
//!
//! A part's EXR holds its mean `m`, its standard error `se` (where its integrator kept
//! second moments and it has two passes or more) and, in its header, a [`PartRecord`].
//! Its film sums come back as `Σ = n·m` and `Σ² = n·m² + n(n−1)·se²` (the sample
//! variance times n − 1 added to n·m², which keeps the variance's precision even where
//! it is small against m²; a one-pass part has `Σ² = m²`). The parts' sums add up, and
//! the merged image and its standard error are those of the summed film.

use std::fmt;
use std::ops::Range;
use std::path::{Path, PathBuf};

use super::part::{self, PartRecord};
use super::shard::{PassRanges, Shard};
use super::RenderError;
use crate::film::{read_exr, Film, FilmSums, RenderMetadata};

/// Header entries a part holds about its own run, left out of the merged header.
const PER_RUN_KEYS: [&str; 4] = ["passes", "rays_traced", "stopped_early", KEY_MERGED_PARTS];
/// How many renders a merged image was merged from: a part merged before counts its own.
const KEY_MERGED_PARTS: &str = "merged_parts";

/// The merged image.
pub struct MergedImage {
    /// Mean, standard error (where the parts carry second moments) and the first
    /// part's AOVs (first-hit AOVs come from one pixel-centre pass: every part has the
    /// same ones).
    pub film: Film,
    pub sums: FilmSums,
    pub metadata: RenderMetadata,
    pub record: PartRecord,
    /// Shards of the parts' shard count that no part is (when all parts are shards of
    /// one count): the merged image is then valid but has fewer samples.
    pub missing_shards: MissingShards,
}

/// Shards of one count that no part is, as runs of indices: a part may be one shard of
/// billions (of a render of as many passes), and the runs are never more than the parts
/// and one.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct MissingShards {
    pub count: u32,
    pub indices: Vec<Range<u32>>,
}

impl MissingShards {
    pub fn is_empty(&self) -> bool {
        self.indices.is_empty()
    }
}

impl fmt::Display for MissingShards {
    /// `1/4, 3/4`; a run of three or more as `4/9 to 7/9`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let n = self.count;
        let runs: Vec<String> = self
            .indices
            .iter()
            .map(|r| match r.end - r.start {
                1 => format!("{}/{n}", r.start),
                2 => format!("{}/{n}, {}/{n}", r.start, r.start + 1),
                _ => format!("{}/{n} to {}/{n}", r.start, r.end - 1),
            })
            .collect();
        f.write_str(&runs.join(", "))
    }
}

/// One part as read.
struct Part {
    path: PathBuf,
    film: Film,
    meta: RenderMetadata,
    record: PartRecord,
}

/// Reads the EXR parts at `paths` and merges them; refuses, naming the file, a part
/// that is missing, unreadable, not a splitray part, of another scene, size or
/// settings, a shard given twice, or one whose passes another part holds too.
pub fn merge_parts(paths: &[impl AsRef<Path>]) -> Result<MergedImage, RenderError> {
    // Generic only in this shim: the merge is compiled once, here, not in every caller.
    merge_paths(&paths.iter().map(AsRef::as_ref).collect::<Vec<&Path>>())
}

fn merge_paths(paths: &[&Path]) -> Result<MergedImage, RenderError> {
    if paths.is_empty() {
        return Err(RenderError::Options("merge needs at least one part".into()));
    }
    let mut parts: Vec<Part> = Vec::with_capacity(paths.len());
    for path in paths {
        let part = read_part(path)?;
        for earlier in &parts {
            check_belongs_with(&part, earlier)?;
        }
        parts.push(part);
    }
    let mut sums: Option<FilmSums> = None;
    let mut passes = PassRanges::default();
    for part in &parts {
        let part_sums = sums_of(part)?;
        for range in part.record.passes.ranges() {
            passes.add(range.clone());
        }
        match &mut sums {
            None => sums = Some(part_sums),
            Some(s) => s.merge(&part_sums).map_err(|m| bad(&part.path, m))?,
        }
    }
    let sums = sums.expect("at least one part");
    let first = &parts[0];
    let record = PartRecord {
        fingerprint: first.record.fingerprint.clone(),
        passes,
        samples_per_pass: first.record.samples_per_pass,
        second_moments: first.record.second_moments,
        shard: None,
    };
    let mut film = sums.to_film()?;
    film.depth = first.film.depth.clone();
    film.normal = first.film.normal.clone();
    film.triangle_id = first.film.triangle_id.clone();
    film.stderr = sums.stderr();
    let metadata = merged_metadata(&parts, &sums, &record);
    Ok(MergedImage {
        film,
        sums,
        metadata,
        record,
        missing_shards: missing_shards(&parts),
    })
}

fn read_part(path: &Path) -> Result<Part, RenderError> {
    let (film, meta) = read_exr(path)?;
    let record = PartRecord::from_metadata(&meta)
        .map_err(|m| bad(path, format!("is not a part of a splitray render: {m}")))?;
    if record.passes.count() == 0 {
        return Err(bad(path, "holds no passes"));
    }
    if record.passes.count() > u32::MAX as u64 {
        return Err(bad(path, "holds more passes than a film can count"));
    }
    Ok(Part {
        path: path.to_path_buf(),
        film,
        meta,
        record,
    })
}

/// Refuses `part` if it cannot be merged with `earlier`.
fn check_belongs_with(part: &Part, earlier: &Part) -> Result<(), RenderError> {
    let (a, b) = (&part.record, &earlier.record);
    let other = earlier.path.display();
    let size = |f: &Film| format!("{}x{}", f.width(), f.height());
    if size(&part.film) != size(&earlier.film) {
        return Err(bad(
            &part.path,
            format!(
                "is {}, {other} is {}: parts of one image have one size",
                size(&part.film),
                size(&earlier.film)
            ),
        ));
    }
    if a.fingerprint != b.fingerprint {
        let here = format!("in {}", part.path.display());
        let there = format!("in {other}");
        let differences = a.fingerprint.differences(&b.fingerprint, &here, &there);
        return Err(bad(
            &part.path,
            format!(
                "was rendered from another scene or settings than {other}: {}",
                differences.join("; ")
            ),
        ));
    }
    if a.second_moments != b.second_moments {
        return Err(bad(
            &part.path,
            format!("keeps second moments where {other} does not, or the reverse"),
        ));
    }
    if let (Some(s), Some(t)) = (a.shard, b.shard) {
        if s == t {
            return Err(bad(
                &part.path,
                format!("is shard {s}, and so is {other}: the same shard twice"),
            ));
        }
    }
    if let Some(overlap) = a.passes.overlap(&b.passes) {
        return Err(bad(
            &part.path,
            format!(
                "holds passes {}..{}, which {other} holds too: merged, they would count \
                 those samples twice",
                overlap.start, overlap.end
            ),
        ));
    }
    Ok(())
}

/// The film sums of one part, rebuilt from its mean and standard error.
fn sums_of(part: &Part) -> Result<FilmSums, RenderError> {
    let n = part.record.passes.count() as u32;
    let mean = part.film.mean_rgb_buffer();
    let (w, h) = (part.film.width(), part.film.height());
    let nf = n as f64;
    let sum: Vec<[f64; 3]> = mean.iter().map(|m| m.map(|v| v as f64 * nf)).collect();
    let sum_sq = match (part.record.second_moments, n, &part.film.stderr) {
        (false, _, _) => None,
        (true, 1, _) => Some(mean.iter().map(|m| m.map(|v| (v as f64).powi(2))).collect()),
        (true, _, Some(se)) => Some(
            mean.iter()
                .zip(se)
                .map(|(m, s)| {
                    let mut q = [0.0; 3];
                    for c in 0..3 {
                        let (m, s) = (m[c] as f64, s[c] as f64);
                        q[c] = nf * m * m + nf * (nf - 1.0) * s * s;
                    }
                    q
                })
                .collect(),
        ),
        (true, _, None) => {
            return Err(bad(
                &part.path,
                "keeps second moments but has no stderr.R/G/B channels",
            ))
        }
    };
    Ok(FilmSums {
        width: w,
        height: h,
        passes: n,
        samples_per_pass: part.record.samples_per_pass,
        sum,
        sum_sq,
    })
}

fn merged_metadata(parts: &[Part], sums: &FilmSums, record: &PartRecord) -> RenderMetadata {
    let first = &parts[0].meta;
    let distinct = |get: &dyn Fn(&RenderMetadata) -> &str, sep: &str| {
        let mut seen: Vec<&str> = Vec::new();
        for p in parts {
            let v = get(&p.meta);
            if !seen.contains(&v) {
                seen.push(v);
            }
        }
        seen.join(sep)
    };
    let mut extra: Vec<(String, String)> = first
        .extra
        .iter()
        .filter(|(k, _)| !part::KEYS.contains(&k.as_str()) && !PER_RUN_KEYS.contains(&k.as_str()))
        .cloned()
        .collect();
    extra.extend(record.extra());
    extra.push(("passes".into(), sums.passes.to_string()));
    let renders: u64 = parts
        .iter()
        .map(|p| {
            let merged = p.meta.extra.iter().find(|(k, _)| k == KEY_MERGED_PARTS);
            merged.and_then(|(_, v)| v.parse().ok()).unwrap_or(1)
        })
        .sum();
    extra.push((KEY_MERGED_PARTS.into(), renders.to_string()));
    RenderMetadata {
        spp: sums.spp().min(u32::MAX as u64) as u32,
        seed: first.seed,
        integrator: first.integrator.clone(),
        tracer: distinct(&|m| &m.tracer, ","),
        device: distinct(&|m| &m.device, "; "),
        render_time_s: parts.iter().map(|p| p.meta.render_time_s).sum(),
        extra,
    }
}

fn missing_shards(parts: &[Part]) -> MissingShards {
    let shards: Option<Vec<Shard>> = parts.iter().map(|p| p.record.shard).collect();
    let Some(mut shards) = shards else {
        return MissingShards::default();
    };
    let count = shards[0].count;
    if shards.iter().any(|s| s.count != count) {
        return MissingShards::default();
    }
    shards.sort_by_key(|s| s.index);
    // The gaps before, between and after the parts' indices.
    let mut indices = Vec::new();
    let mut next = 0;
    for s in &shards {
        if s.index > next {
            indices.push(next..s.index);
        }
        next = next.max(s.index + 1);
    }
    if next < count {
        indices.push(next..count);
    }
    MissingShards { count, indices }
}

fn bad(path: &Path, message: impl Into<String>) -> RenderError {
    RenderError::BadFile {
        path: path.to_path_buf(),
        message: message.into(),
    }
}
