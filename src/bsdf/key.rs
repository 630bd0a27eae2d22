//! Material keys (thesis §4.4.2): a 32-bit key whose 8 high bits are the material type
//! and whose 24 low bits are the material id, so that sorting hit records by key groups
//! them by type first (coherent shading) and by material within a type.
//! `material_key_type` / `material_key_id` in `bsdf.glsl` are the GLSL twins.

use super::{kind, BsdfParams};

/// Bits of the id field.
pub const MATERIAL_ID_BITS: u32 = 24;
/// Largest id + 1.
pub const MATERIAL_ID_LIMIT: u32 = 1 << MATERIAL_ID_BITS;

/// The material type in a key's high byte: the single-layer BSDF kinds (same values as
/// [`kind`]), `Layered` for stacks of more than one layer, `Emissive` for lights.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
#[repr(u8)]
pub enum MaterialType {
    Lambert = kind::LAMBERT as u8,
    OrenNayar = kind::OREN_NAYAR as u8,
    Mirror = kind::MIRROR as u8,
    Dielectric = kind::DIELECTRIC as u8,
    MicrofacetReflection = kind::MICROFACET_REFLECTION as u8,
    MicrofacetDielectric = kind::MICROFACET_DIELECTRIC as u8,
    Layered = 6,
    Emissive = 7,
}

impl MaterialType {
    /// The type of a BSDF stack: its kind for one layer, `Layered` otherwise (`None`
    /// for an unknown kind).
    pub fn of(params: &BsdfParams) -> Option<Self> {
        let layers = params.active();
        if layers.len() != 1 {
            return Some(Self::Layered);
        }
        Self::from_u8(u8::try_from(layers[0].kind).ok()?)
    }

    pub fn from_u8(v: u8) -> Option<Self> {
        Some(match v {
            0 => Self::Lambert,
            1 => Self::OrenNayar,
            2 => Self::Mirror,
            3 => Self::Dielectric,
            4 => Self::MicrofacetReflection,
            5 => Self::MicrofacetDielectric,
            6 => Self::Layered,
            7 => Self::Emissive,
            _ => return None,
        })
    }
}

/// Why a key could not be made.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
pub enum MaterialKeyError {
    #[error("material id {0} does not fit in the key's 24 bits (limit {MATERIAL_ID_LIMIT})")]
    IdTooLarge(u32),
}

/// `(type << 24) | id`, or an error when `id ≥ 2^24`.
pub fn try_material_key(ty: MaterialType, id: u32) -> Result<u32, MaterialKeyError> {
    if id >= MATERIAL_ID_LIMIT {
        return Err(MaterialKeyError::IdTooLarge(id));
    }
    Ok(((ty as u32) << MATERIAL_ID_BITS) | id)
}

/// `(type << 24) | id`; panics when `id ≥ 2^24` (see [`try_material_key`]).
pub fn material_key(ty: MaterialType, id: u32) -> u32 {
    match try_material_key(ty, id) {
        Ok(k) => k,
        Err(e) => panic!("{e}"),
    }
}

/// The type byte of a key.
pub fn key_type(key: u32) -> u8 {
    (key >> MATERIAL_ID_BITS) as u8
}

/// The id of a key.
pub fn key_id(key: u32) -> u32 {
    key & (MATERIAL_ID_LIMIT - 1)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keys_pack_type_high_and_id_low() {
        let k = material_key(MaterialType::MicrofacetDielectric, 0x00AB_CDEF);
        assert_eq!(k, 0x05AB_CDEF);
        assert_eq!(key_type(k), MaterialType::MicrofacetDielectric as u8);
        assert_eq!(key_id(k), 0x00AB_CDEF);
        let max = material_key(MaterialType::Emissive, MATERIAL_ID_LIMIT - 1);
        assert_eq!(max, 0x07FF_FFFF);
        assert_eq!(
            try_material_key(MaterialType::Lambert, MATERIAL_ID_LIMIT),
            Err(MaterialKeyError::IdTooLarge(MATERIAL_ID_LIMIT))
        );
        for v in 0..=7u8 {
            assert_eq!(MaterialType::from_u8(v).map(|t| t as u8), Some(v));
        }
        assert_eq!(MaterialType::from_u8(8), None);
    }

    #[test]
    fn keys_sort_by_type_then_id() {
        let mut keys = [
            material_key(MaterialType::Layered, 1),
            material_key(MaterialType::Lambert, 900),
            material_key(MaterialType::Layered, 0),
            material_key(MaterialType::Lambert, 3),
        ];
        keys.sort_unstable();
        let types: Vec<u8> = keys.iter().map(|&k| key_type(k)).collect();
        assert_eq!(types, [0, 0, 6, 6]);
        assert_eq!(key_id(keys[0]), 3);
    }

    #[test]
    #[should_panic(expected = "24 bits")]
    fn oversized_id_panics() {
        material_key(MaterialType::Mirror, 1 << 24);
    }
}
