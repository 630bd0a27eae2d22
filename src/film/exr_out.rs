//! OpenEXR output and input of a [`Film`].
//!
//! # File layout
//! One **single-part** scan-line EXR, ZIP compressed (lossless, bit-exact), with all
//! channels in one layer, using the OpenEXR `layer.channel` naming convention for AOVs.
//! Single-part files are what every EXR reader handles; tools that understand the naming
//! convention (Nuke, Blender, OpenImageIO, ...) show `depth` and `normal` as layers.
//!
//! | channel                          | type | content                                        |
//! |----------------------------------|------|------------------------------------------------|
//! | `R`, `G`, `B`                    | f32  | linear radiance estimate ([`Film::mean_rgb`])  |
//! | `depth.Z`                        | f32  | hit distance along the unit ray, `+inf` = miss |
//! | `normal.X`, `normal.Y`, `normal.Z` | f32 | normal AOV                                    |
//! | `triangle_id`                    | u32  | hit triangle, `u32::MAX` = miss                |
//! | `stderr.R`, `stderr.G`, `stderr.B` | f32 | standard error of `R`, `G`, `B`              |
//!
//! AOV channels are present only when the film has that AOV. Row 0 of the film is the top
//! scan line of the file (EXR's y axis points down, as the film's does).
//!
//! # Metadata
//! [`RenderMetadata`] becomes custom header attributes:
//!
//! | attribute                | EXR type | note                                             |
//! |--------------------------|----------|--------------------------------------------------|
//! | `splitray.spp`           | int      | `string` (decimal) if it exceeds `i32::MAX`      |
//! | `splitray.seed`          | string   | decimal; EXR has no 64-bit integer attribute     |
//! | `splitray.integrator`    | string   |                                                  |
//! | `splitray.tracer`        | string   |                                                  |
//! | `splitray.device`        | string   |                                                  |
//! | `splitray.render_time_s` | double   |                                                  |
//! | `splitray.extra.<key>`   | string   | one per `extra` entry                            |
//!
//! Strings are stored as their UTF-8 bytes. The standard `software` attribute is set to
//! `splitray <version>`.

use std::collections::HashMap;
use std::io::{BufReader, Seek, Write};
use std::path::Path;

use exr::image::{AnyChannel, AnyChannels, Encoding, FlatSamples, Image, Layer};
use exr::meta::attribute::{AttributeValue, Text};
use exr::meta::header::LayerAttributes;
use exr::prelude::{ReadChannels, ReadLayers, SmallVec, WritableImage};

use super::atomic::AtomicFile;
use super::{Film, FilmError, RenderMetadata};

/// Channel names, see the module documentation.
pub const CHANNEL_DEPTH: &str = "depth.Z";
/// Triangle-id channel name (u32 samples).
pub const CHANNEL_TRIANGLE_ID: &str = "triangle_id";
/// Normal channel names.
pub const CHANNELS_NORMAL: [&str; 3] = ["normal.X", "normal.Y", "normal.Z"];
/// Standard-error channel names.
pub const CHANNELS_STDERR: [&str; 3] = ["stderr.R", "stderr.G", "stderr.B"];

const ATTR_SPP: &str = "splitray.spp";
const ATTR_SEED: &str = "splitray.seed";
const ATTR_INTEGRATOR: &str = "splitray.integrator";
const ATTR_TRACER: &str = "splitray.tracer";
const ATTR_DEVICE: &str = "splitray.device";
const ATTR_RENDER_TIME: &str = "splitray.render_time_s";
const ATTR_EXTRA_PREFIX: &str = "splitray.extra.";

/// Writes `film` and `meta` to the EXR file `path`, atomically (see [`super::atomic`]).
///
/// Non-finite pixels are written as they are (EXR is HDR) and reported with a warning.
pub fn write_exr(
    path: impl AsRef<Path>,
    film: &Film,
    meta: &RenderMetadata,
) -> Result<(), FilmError> {
    let path = path.as_ref();
    let mut file = AtomicFile::create(path)?;
    encode_exr(film, meta, file.writer(), path)?;
    warn_non_finite(film, path);
    file.commit()?;
    Ok(())
}

pub(crate) fn warn_non_finite(film: &Film, path: &Path) -> usize {
    let n = film.count_non_finite();
    if n > 0 {
        log::warn!(
            "{}: {n} of {} pixels have a NaN or infinite estimate",
            path.display(),
            film.pixel_count()
        );
    }
    n
}

fn text(s: &str) -> Text {
    Text::from_slice_unchecked(s.as_bytes())
}

fn text_to_string(t: &Text) -> String {
    let bytes = t.bytes();
    match std::str::from_utf8(bytes) {
        Ok(s) => s.to_owned(),
        // Not UTF-8: interpret as Latin-1, which is what the exr crate itself produces.
        Err(_) => bytes.iter().map(|&b| char::from(b)).collect(),
    }
}

fn metadata_attributes(
    meta: &RenderMetadata,
    path: &Path,
) -> Result<HashMap<Text, AttributeValue>, FilmError> {
    let mut attrs = HashMap::new();
    let spp = match i32::try_from(meta.spp) {
        Ok(v) => AttributeValue::I32(v),
        Err(_) => AttributeValue::Text(text(&meta.spp.to_string())),
    };
    attrs.insert(text(ATTR_SPP), spp);
    attrs.insert(
        text(ATTR_SEED),
        AttributeValue::Text(text(&meta.seed.to_string())),
    );
    attrs.insert(
        text(ATTR_INTEGRATOR),
        AttributeValue::Text(text(&meta.integrator)),
    );
    attrs.insert(text(ATTR_TRACER), AttributeValue::Text(text(&meta.tracer)));
    attrs.insert(text(ATTR_DEVICE), AttributeValue::Text(text(&meta.device)));
    attrs.insert(
        text(ATTR_RENDER_TIME),
        AttributeValue::F64(meta.render_time_s),
    );
    for (key, value) in &meta.extra {
        let name = format!("{ATTR_EXTRA_PREFIX}{key}");
        if key.is_empty() || key.contains('\0') || name.len() > 255 {
            return Err(FilmError::invalid(
                path,
                format!("metadata key {key:?} is empty, contains NUL or is too long"),
            ));
        }
        if attrs
            .insert(text(&name), AttributeValue::Text(text(value)))
            .is_some()
        {
            return Err(FilmError::invalid(
                path,
                format!("duplicate metadata key {key:?}"),
            ));
        }
    }
    Ok(attrs)
}

/// Encodes `film` as EXR into `out`; `path` is only used in error messages.
pub(crate) fn encode_exr<W: Write + Seek>(
    film: &Film,
    meta: &RenderMetadata,
    out: W,
    path: &Path,
) -> Result<(), FilmError> {
    if film.pixel_count() == 0 {
        return Err(FilmError::invalid(
            path,
            format!(
                "cannot write an empty {}x{} film",
                film.width(),
                film.height()
            ),
        ));
    }
    film.validate_aovs()?;

    let rgb = film.mean_rgb_buffer();
    let mut channels: Vec<AnyChannel<FlatSamples>> = ["R", "G", "B"]
        .iter()
        .enumerate()
        .map(|(c, name)| {
            AnyChannel::new(*name, FlatSamples::F32(rgb.iter().map(|p| p[c]).collect()))
        })
        .collect();
    drop(rgb);
    if let Some(depth) = &film.depth {
        channels.push(AnyChannel::new(
            CHANNEL_DEPTH,
            FlatSamples::F32(depth.clone()),
        ));
    }
    if let Some(normal) = &film.normal {
        for (c, name) in CHANNELS_NORMAL.iter().enumerate() {
            channels.push(AnyChannel::new(
                *name,
                FlatSamples::F32(normal.iter().map(|n| n[c]).collect()),
            ));
        }
    }
    if let Some(stderr) = &film.stderr {
        for (c, name) in CHANNELS_STDERR.iter().enumerate() {
            channels.push(AnyChannel::new(
                *name,
                FlatSamples::F32(stderr.iter().map(|s| s[c]).collect()),
            ));
        }
    }
    if let Some(ids) = &film.triangle_id {
        channels.push(AnyChannel::new(
            CHANNEL_TRIANGLE_ID,
            FlatSamples::U32(ids.clone()),
        ));
    }

    let mut attributes = LayerAttributes {
        software_name: Some(text(&format!("splitray {}", env!("CARGO_PKG_VERSION")))),
        ..LayerAttributes::default()
    };
    attributes.other = metadata_attributes(meta, path)?;

    let layer = Layer::new(
        (film.width() as usize, film.height() as usize),
        attributes,
        Encoding::SMALL_LOSSLESS,
        AnyChannels::sort(SmallVec::from_vec(channels)),
    );
    Image::from_layer(layer)
        .write()
        .to_buffered(out)
        .map_err(|error| FilmError::Exr {
            path: path.to_path_buf(),
            error,
        })
}

/// Reads an EXR written by [`write_exr`] (or any EXR with at least `R`, `G`, `B`
/// channels) back into a film and its metadata.
///
/// The returned film holds the stored estimate as a single pass ([`Film::from_mean_rgb`]),
/// so `mean_rgb` returns the stored values bit-exactly; the original sample count is in
/// `RenderMetadata::spp`. Accepted channel names: `R`/`G`/`B` (f16 or f32), depth as
/// `depth.Z`, `depth` or `Z`; `triangle_id` must be u32. Metadata attributes that are
/// absent keep their [`Default`] value; `extra` comes back sorted by key.
pub fn read_exr(path: impl AsRef<Path>) -> Result<(Film, RenderMetadata), FilmError> {
    let path = path.as_ref();
    let file = std::fs::File::open(path).map_err(|e| FilmError::io(path, "open", e))?;
    let image = exr::prelude::read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .all_layers()
        .all_attributes()
        .from_buffered(BufReader::new(file))
        .map_err(|error| FilmError::Exr {
            path: path.to_path_buf(),
            error,
        })?;

    // Gather channels of all layers under their full `layer.channel` names.
    let mut size = None;
    let mut channels: HashMap<String, &FlatSamples> = HashMap::new();
    let mut attrs: HashMap<&Text, &AttributeValue> = image.attributes.other.iter().collect();
    for layer in &image.layer_data {
        attrs.extend(layer.attributes.other.iter());
        let prefix = layer
            .attributes
            .layer_name
            .as_ref()
            .map(|n| format!("{}.", text_to_string(n)))
            .unwrap_or_default();
        for ch in &layer.channel_data.list {
            let name = format!("{prefix}{}", text_to_string(&ch.name));
            if name == "R" || name == "G" || name == "B" {
                size = Some(layer.size);
            }
            channels.insert(name, &ch.sample_data);
        }
    }
    let size = size.ok_or_else(|| FilmError::invalid(path, "no R/G/B channels"))?;
    let (width, height) = match (u32::try_from(size.0), u32::try_from(size.1)) {
        (Ok(w), Ok(h)) => (w, h),
        _ => return Err(FilmError::invalid(path, "image too large")),
    };
    let n = size.0 * size.1;

    let f32_channel = |name: &str| -> Result<Option<Vec<f32>>, FilmError> {
        let Some(samples) = channels.get(name) else {
            return Ok(None);
        };
        let values: Vec<f32> = match samples {
            FlatSamples::F32(v) => v.clone(),
            FlatSamples::F16(v) => v.iter().map(|h| h.to_f32()).collect(),
            FlatSamples::U32(_) => {
                return Err(FilmError::invalid(
                    path,
                    format!("channel {name} has u32 samples, expected float"),
                ))
            }
        };
        if values.len() != n {
            return Err(FilmError::invalid(
                path,
                format!("channel {name} has {} samples, expected {n}", values.len()),
            ));
        }
        Ok(Some(values))
    };
    let required = |name: &str| {
        f32_channel(name)?
            .ok_or_else(|| FilmError::invalid(path, format!("missing channel {name}")))
    };
    let (r, g, b) = (required("R")?, required("G")?, required("B")?);
    let rgb: Vec<[f32; 3]> = (0..n).map(|i| [r[i], g[i], b[i]]).collect();
    let mut film = Film::from_mean_rgb(width, height, &rgb)?;

    for name in [CHANNEL_DEPTH, "depth", "Z"] {
        if let Some(depth) = f32_channel(name)? {
            film.depth = Some(depth);
            break;
        }
    }
    let normal: Vec<Option<Vec<f32>>> = CHANNELS_NORMAL
        .iter()
        .map(|name| f32_channel(name))
        .collect::<Result<_, _>>()?;
    if let [Some(x), Some(y), Some(z)] = normal.as_slice() {
        film.normal = Some((0..n).map(|i| [x[i], y[i], z[i]]).collect());
    }
    let stderr: Vec<Option<Vec<f32>>> = CHANNELS_STDERR
        .iter()
        .map(|name| f32_channel(name))
        .collect::<Result<_, _>>()?;
    if let [Some(r), Some(g), Some(b)] = stderr.as_slice() {
        film.stderr = Some((0..n).map(|i| [r[i], g[i], b[i]]).collect());
    }
    match channels.get(CHANNEL_TRIANGLE_ID) {
        None => {}
        Some(FlatSamples::U32(ids)) if ids.len() == n => film.triangle_id = Some(ids.clone()),
        Some(_) => {
            return Err(FilmError::invalid(
                path,
                format!("channel {CHANNEL_TRIANGLE_ID} must have {n} u32 samples"),
            ))
        }
    }

    let meta = parse_metadata(&attrs, path)?;
    Ok((film, meta))
}

fn parse_metadata(
    attrs: &HashMap<&Text, &AttributeValue>,
    path: &Path,
) -> Result<RenderMetadata, FilmError> {
    let get = |name: &str| attrs.get(&text(name)).copied();
    let bad = |name: &str| FilmError::invalid(path, format!("attribute {name} has a bad value"));
    let string = |name: &str| -> Result<Option<String>, FilmError> {
        match get(name) {
            None => Ok(None),
            Some(AttributeValue::Text(t)) => Ok(Some(text_to_string(t))),
            Some(_) => Err(bad(name)),
        }
    };

    let mut meta = RenderMetadata::default();
    match get(ATTR_SPP) {
        None => {}
        Some(AttributeValue::I32(v)) => meta.spp = u32::try_from(*v).map_err(|_| bad(ATTR_SPP))?,
        Some(AttributeValue::Text(t)) => {
            meta.spp = text_to_string(t).parse().map_err(|_| bad(ATTR_SPP))?;
        }
        Some(_) => return Err(bad(ATTR_SPP)),
    }
    if let Some(s) = string(ATTR_SEED)? {
        meta.seed = s.parse().map_err(|_| bad(ATTR_SEED))?;
    }
    meta.integrator = string(ATTR_INTEGRATOR)?.unwrap_or_default();
    meta.tracer = string(ATTR_TRACER)?.unwrap_or_default();
    meta.device = string(ATTR_DEVICE)?.unwrap_or_default();
    match get(ATTR_RENDER_TIME) {
        None => {}
        Some(AttributeValue::F64(v)) => meta.render_time_s = *v,
        Some(AttributeValue::F32(v)) => meta.render_time_s = f64::from(*v),
        Some(_) => return Err(bad(ATTR_RENDER_TIME)),
    }
    for (name, value) in attrs {
        let name = text_to_string(name);
        if let Some(key) = name.strip_prefix(ATTR_EXTRA_PREFIX) {
            match value {
                AttributeValue::Text(t) => meta.extra.push((key.to_owned(), text_to_string(t))),
                _ => return Err(bad(&name)),
            }
        }
    }
    meta.extra.sort();
    Ok(meta)
}
