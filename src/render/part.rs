//! [`PartRecord`]: what an image's header records so that parts of one image (shards,
//! or images merged before) can be merged: the fingerprint of its scene and settings,
//! the passes it holds by global index, and how to rebuild its film sums.

use super::fingerprint::Fingerprint;
use super::shard::{PassRanges, Shard};
use crate::film::RenderMetadata;

const KEY_FINGERPRINT: &str = "fingerprint";
const KEY_SCENE_DIGEST: &str = "scene_digest";
const KEY_SETTINGS: &str = "image_settings";
const KEY_PASS_RANGES: &str = "pass_ranges";
const KEY_SAMPLES_PER_PASS: &str = "samples_per_pass";
const KEY_SECOND_MOMENTS: &str = "second_moments";
const KEY_SHARD: &str = "shard";

/// The keys of [`PartRecord::extra`]: a merged image writes its own values of them.
pub const KEYS: [&str; 7] = [
    KEY_FINGERPRINT,
    KEY_SCENE_DIGEST,
    KEY_SETTINGS,
    KEY_PASS_RANGES,
    KEY_SAMPLES_PER_PASS,
    KEY_SECOND_MOMENTS,
    KEY_SHARD,
];

#[derive(Clone, Debug, PartialEq)]
pub struct PartRecord {
    pub fingerprint: Fingerprint,
    /// The passes the image holds, by global pass index.
    pub passes: PassRanges,
    pub samples_per_pass: u32,
    /// Whether the film kept Σ estimate² (then an image of two passes or more carries
    /// its standard error, and the merged image gets one too).
    pub second_moments: bool,
    /// The shard it was rendered as; `None` for a whole render or a merged image.
    pub shard: Option<Shard>,
}

impl PartRecord {
    /// Header entries (`RenderMetadata::extra`) holding the record.
    pub fn extra(&self) -> Vec<(String, String)> {
        let mut out = vec![
            (KEY_FINGERPRINT.to_string(), self.fingerprint.hash()),
            (
                KEY_SCENE_DIGEST.to_string(),
                self.fingerprint.scene_digest.clone(),
            ),
            (KEY_SETTINGS.to_string(), self.fingerprint.settings_string()),
            (KEY_PASS_RANGES.to_string(), self.passes.to_string()),
            (
                KEY_SAMPLES_PER_PASS.to_string(),
                self.samples_per_pass.to_string(),
            ),
            (
                KEY_SECOND_MOMENTS.to_string(),
                self.second_moments.to_string(),
            ),
        ];
        if let Some(shard) = self.shard {
            out.push((KEY_SHARD.to_string(), shard.to_string()));
        }
        out
    }

    /// Reads the record back; the error says what is missing or malformed.
    pub fn from_metadata(meta: &RenderMetadata) -> Result<Self, String> {
        let get = |key: &str| {
            meta.extra
                .iter()
                .find(|(k, _)| k == key)
                .map(|(_, v)| v.as_str())
        };
        let Some(hash) = get(KEY_FINGERPRINT) else {
            return Err(
                "its header has no splitray.extra.fingerprint: it is not an image \
                        rendered by splitray render (or it predates shards)"
                    .into(),
            );
        };
        let required =
            |key: &str| get(key).ok_or_else(|| format!("its header lacks splitray.extra.{key}"));
        let bad = |key: &str, value: &str| format!("splitray.extra.{key} {value:?} is malformed");
        let settings_text = required(KEY_SETTINGS)?;
        let settings = Fingerprint::parse_settings(settings_text)
            .ok_or_else(|| bad(KEY_SETTINGS, settings_text))?;
        let fingerprint = Fingerprint {
            scene_digest: required(KEY_SCENE_DIGEST)?.to_string(),
            settings,
        };
        if fingerprint.hash() != hash {
            return Err(
                "its fingerprint does not match the scene digest and settings \
                        beside it (the header was edited or damaged)"
                    .into(),
            );
        }
        let ranges = required(KEY_PASS_RANGES)?;
        let samples = required(KEY_SAMPLES_PER_PASS)?;
        let moments = required(KEY_SECOND_MOMENTS)?;
        Ok(Self {
            fingerprint,
            passes: ranges.parse().map_err(|_| bad(KEY_PASS_RANGES, ranges))?,
            samples_per_pass: samples
                .parse()
                .ok()
                .filter(|&s| s > 0)
                .ok_or_else(|| bad(KEY_SAMPLES_PER_PASS, samples))?,
            second_moments: moments
                .parse()
                .map_err(|_| bad(KEY_SECOND_MOMENTS, moments))?,
            shard: match get(KEY_SHARD) {
                None => None,
                Some(s) => Some(s.parse().map_err(|_| bad(KEY_SHARD, s))?),
            },
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_record_round_trips_through_header_entries() {
        let record = PartRecord {
            fingerprint: Fingerprint {
                scene_digest: "ab".repeat(32),
                settings: vec![("width".into(), "4".into()), ("seed".into(), "1".into())],
            },
            passes: "0..3,8..9".parse().unwrap(),
            samples_per_pass: 1,
            second_moments: true,
            shard: Some(Shard::new(1, 4).unwrap()),
        };
        let meta = RenderMetadata {
            extra: record.extra(),
            ..Default::default()
        };
        assert_eq!(PartRecord::from_metadata(&meta).unwrap(), record);

        let mut edited = meta.clone();
        edited.extra[2].1 = "width=4;seed=2".into();
        let err = PartRecord::from_metadata(&edited).unwrap_err();
        assert!(err.contains("does not match"), "{err}");
        let foreign = RenderMetadata::default();
        let err = PartRecord::from_metadata(&foreign).unwrap_err();
        assert!(err.contains("fingerprint"), "{err}");
    }
}
