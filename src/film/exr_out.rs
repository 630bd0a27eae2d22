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

use exr::image::{AnyChannel, AnyChannels, Encoding, FlatSamples, Image, Layer, Layers};
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
    // Generic only in this shim: the encoder is compiled once, here, not in every caller.
    write_exr_at(path.as_ref(), film, meta)
}

fn write_exr_at(path: &Path, film: &Film, meta: &RenderMetadata) -> Result<(), FilmError> {
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
    film.refuse_empty(path)?;
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
    let image = read_exr_image(path)?;
    let film = ExrChannels::gather(&image, path)?.film()?;
    let meta = parse_metadata(&exr_attributes(&image), path)?;
    Ok((film, meta))
}

/// An EXR as read: every channel of every layer, at its largest resolution.
type ExrImage = Image<Layers<AnyChannels<FlatSamples>>>;

fn read_exr_image(path: &Path) -> Result<ExrImage, FilmError> {
    let mut file = crate::input::open(path).map_err(|e| FilmError::io(path, "open", e))?;
    check_exr_size(&mut file, path)?;
    exr::prelude::read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .all_layers()
        .all_attributes()
        .from_buffered(BufReader::new(file))
        .map_err(|error| FilmError::Exr {
            path: path.to_path_buf(),
            error,
        })
}

/// How many times larger than its file an EXR's pixels may be. Deflate (ZIP, the
/// compression splitray writes, and PXR24's last step) shrinks data at most 1032 times;
/// the margin above that leaves room for the run-length stages of PIZ and DWA on images
/// of one colour.
const MAX_EXR_EXPANSION: u128 = 4096;

/// Pixel bytes any EXR may describe whatever its file's size (a 2048² RGBA f32 image):
/// a small image of one colour compressed past [`MAX_EXR_EXPANSION`] is read, and a
/// corrupted header of a small file costs at most this much memory.
const ALWAYS_READ_PIXEL_BYTES: u128 = 64 << 20;

/// Refuses, from its header, an EXR whose pixels no film could hold or its file could
/// not encode: the decoder sizes its sample buffers by the header alone, so a corrupted
/// data window or channel list would otherwise make it allocate gigabytes for a file of
/// a few hundred bytes. Leaves `file` at its start.
fn check_exr_size(file: &mut std::fs::File, path: &Path) -> Result<(), FilmError> {
    let exr_error = |error| FilmError::Exr {
        path: path.to_path_buf(),
        error,
    };
    let file_len = file
        .metadata()
        .map_err(|e| FilmError::io(path, "read", e))?
        .len();
    let meta = exr::meta::MetaData::read_from_buffered(BufReader::new(&mut *file), false)
        .map_err(exr_error)?;
    file.rewind().map_err(|e| FilmError::io(path, "read", e))?;
    let max_side = crate::scene::validate::MAX_FILM_DIM as usize;
    let mut pixel_bytes: u128 = 0;
    for header in &meta.headers {
        let (width, height) = (header.layer_size.0, header.layer_size.1);
        if width > max_side || height > max_side {
            return Err(FilmError::invalid(
                path,
                format!(
                    "its data window is {width}x{height} pixels, larger than any film \
                     ({max_side}x{max_side}): the header is corrupted, or the image is not one \
                     splitray can read"
                ),
            ));
        }
        let sample_bytes: usize = header
            .channels
            .list
            .iter()
            .map(|c| c.sample_type.bytes_per_sample())
            .sum();
        pixel_bytes += (width * height) as u128 * sample_bytes as u128;
    }
    if pixel_bytes > (u128::from(file_len) * MAX_EXR_EXPANSION).max(ALWAYS_READ_PIXEL_BYTES) {
        return Err(FilmError::invalid(
            path,
            format!(
                "its header describes {pixel_bytes} bytes of pixels, more than \
                 {MAX_EXR_EXPANSION} times the file's {file_len} bytes: the header is \
                 corrupted or the file cut short"
            ),
        ));
    }
    Ok(())
}

/// The image's attributes and every layer's.
fn exr_attributes(image: &ExrImage) -> HashMap<&Text, &AttributeValue> {
    let mut attrs: HashMap<&Text, &AttributeValue> = image.attributes.other.iter().collect();
    for layer in &image.layer_data {
        attrs.extend(layer.attributes.other.iter());
    }
    attrs
}

/// The channels of an EXR's layers, checked against the size of its `R`/`G`/`B` layer.
struct ExrChannels<'a> {
    /// Every channel under its full `layer.channel` name.
    by_name: HashMap<String, &'a FlatSamples>,
    width: u32,
    height: u32,
    /// Pixels: the samples a channel must hold.
    n: usize,
    /// The file, for error messages.
    path: &'a Path,
}

impl<'a> ExrChannels<'a> {
    /// Every layer's channels; refused when none is `R`, `G` or `B`, or when the image is
    /// too large for a film.
    fn gather(image: &'a ExrImage, path: &'a Path) -> Result<Self, FilmError> {
        // Gather channels of all layers under their full `layer.channel` names.
        let mut size = None;
        let mut by_name: HashMap<String, &FlatSamples> = HashMap::new();
        for layer in &image.layer_data {
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
                by_name.insert(name, &ch.sample_data);
            }
        }
        let size = size.ok_or_else(|| FilmError::invalid(path, "no R/G/B channels"))?;
        let (width, height) = match (u32::try_from(size.0), u32::try_from(size.1)) {
            (Ok(w), Ok(h)) => (w, h),
            _ => return Err(FilmError::invalid(path, "image too large")),
        };
        Ok(Self {
            by_name,
            width,
            height,
            n: size.0 * size.1,
            path,
        })
    }

    /// The film these channels hold: the estimate, with whichever AOVs and standard error
    /// the file has.
    fn film(&self) -> Result<Film, FilmError> {
        let (r, g, b) = (
            self.required_channel("R")?,
            self.required_channel("G")?,
            self.required_channel("B")?,
        );
        let mut film = Film::from_mean_rgb(self.width, self.height, &interleave(&r, &g, &b))?;
        if let Some(depth) = self.depth()? {
            film.depth = Some(depth);
        }
        if let Some(normal) = self.float_triples(CHANNELS_NORMAL)? {
            film.normal = Some(normal);
        }
        if let Some(stderr) = self.float_triples(CHANNELS_STDERR)? {
            film.stderr = Some(stderr);
        }
        if let Some(ids) = self.triangle_ids()? {
            film.triangle_id = Some(ids);
        }
        Ok(film)
    }

    /// Channel `name` as f32 samples; `None` when the file has no such channel.
    fn float_channel(&self, name: &str) -> Result<Option<Vec<f32>>, FilmError> {
        let n = self.n;
        let Some(samples) = self.by_name.get(name) else {
            return Ok(None);
        };
        let values: Vec<f32> = match samples {
            FlatSamples::F32(v) => v.clone(),
            FlatSamples::F16(v) => v.iter().map(|h| h.to_f32()).collect(),
            FlatSamples::U32(_) => {
                return Err(FilmError::invalid(
                    self.path,
                    format!("channel {name} has u32 samples, expected float"),
                ))
            }
        };
        if values.len() != n {
            return Err(FilmError::invalid(
                self.path,
                format!("channel {name} has {} samples, expected {n}", values.len()),
            ));
        }
        Ok(Some(values))
    }

    fn required_channel(&self, name: &str) -> Result<Vec<f32>, FilmError> {
        self.float_channel(name)?
            .ok_or_else(|| FilmError::invalid(self.path, format!("missing channel {name}")))
    }

    /// Depth under the first of its accepted names the file has.
    fn depth(&self) -> Result<Option<Vec<f32>>, FilmError> {
        for name in [CHANNEL_DEPTH, "depth", "Z"] {
            if let Some(depth) = self.float_channel(name)? {
                return Ok(Some(depth));
            }
        }
        Ok(None)
    }

    /// The three channels `names` as one triple per pixel; `None` unless all three are
    /// there.
    fn float_triples(&self, names: [&str; 3]) -> Result<Option<Vec<[f32; 3]>>, FilmError> {
        let channels: Vec<Option<Vec<f32>>> = names
            .iter()
            .map(|name| self.float_channel(name))
            .collect::<Result<_, _>>()?;
        Ok(match channels.as_slice() {
            [Some(x), Some(y), Some(z)] => Some(interleave(x, y, z)),
            _ => None,
        })
    }

    fn triangle_ids(&self) -> Result<Option<Vec<u32>>, FilmError> {
        let n = self.n;
        match self.by_name.get(CHANNEL_TRIANGLE_ID) {
            None => Ok(None),
            Some(FlatSamples::U32(ids)) if ids.len() == n => Ok(Some(ids.clone())),
            Some(_) => Err(FilmError::invalid(
                self.path,
                format!("channel {CHANNEL_TRIANGLE_ID} must have {n} u32 samples"),
            )),
        }
    }
}

/// One triple per pixel from three channels of equal length.
fn interleave(a: &[f32], b: &[f32], c: &[f32]) -> Vec<[f32; 3]> {
    a.iter()
        .zip(b)
        .zip(c)
        .map(|((&a, &b), &c)| [a, b, c])
        .collect()
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
