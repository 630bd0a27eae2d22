//! What a pipeline needs to know about its kernel's interface, read from the SPIR-V:
//! which storage buffers it declares as descriptors (set 0) and which it takes by device
//! address, as buffer references at the end of its push-constant block.
//!
//! The convention (glsl/common/address.glsl): a kernel with k buffer references in its
//! push-constant block (after its values) takes its bindings `0..k` by address, in order
//! of the references' offsets, and declares bindings `k..n` as descriptors. So call sites
//! bind buffers the same way whichever way a kernel reads them, and a buffer passed by
//! address may be as large as a VkBuffer can be instead of one storage binding
//! (maxStorageBufferRange: 128 MiB on lavapipe). The references come first because they
//! are what the module reliably shows: the optimiser drops descriptors a variant never
//! uses, but never a member of the push-constant block.

use std::collections::{BTreeSet, HashMap};

const OP_TYPE_STRUCT: u32 = 30;
const OP_TYPE_POINTER: u32 = 32;
const OP_TYPE_FORWARD_POINTER: u32 = 39;
const OP_VARIABLE: u32 = 59;
const OP_DECORATE: u32 = 71;
const OP_MEMBER_DECORATE: u32 = 72;
const DECORATION_BINDING: u32 = 33;
const DECORATION_DESCRIPTOR_SET: u32 = 34;
const DECORATION_OFFSET: u32 = 35;
const STORAGE_PUSH_CONSTANT: u32 = 9;
const STORAGE_PHYSICAL_STORAGE_BUFFER: u32 = 5349;

/// A kernel's buffer interface.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct KernelInterface {
    /// Bindings of set 0 declared as descriptors.
    pub descriptor_bindings: BTreeSet<u32>,
    /// Byte offsets of the push-constant block's buffer-reference members, ascending.
    pub address_offsets: Vec<u32>,
    /// Byte offsets of the push-constant block's other members.
    pub value_offsets: Vec<u32>,
}

/// Reads the interface from SPIR-V words; `None` when they are not well-formed SPIR-V.
pub fn kernel_interface(words: &[u32]) -> Option<KernelInterface> {
    const HEADER: usize = 5;
    if words.len() < HEADER || words[0] != 0x0723_0203 {
        return None;
    }
    let mut binding = HashMap::new();
    let mut set = HashMap::new();
    let mut member_offsets: HashMap<(u32, u32), u32> = HashMap::new();
    let mut pointers = HashMap::new(); // pointer type -> (storage class, pointee)
    let mut structs: HashMap<u32, Vec<u32>> = HashMap::new();
    let mut push_block_pointer = None;
    let mut variables = Vec::new(); // (id, pointer type)
    let mut at = HEADER;
    while at < words.len() {
        let count = (words[at] >> 16) as usize;
        let opcode = words[at] & 0xFFFF;
        if count == 0 || at + count > words.len() {
            return None;
        }
        let ops = &words[at + 1..at + count];
        match (opcode, ops) {
            (OP_DECORATE, [id, DECORATION_BINDING, b, ..]) => {
                binding.insert(*id, *b);
            }
            (OP_DECORATE, [id, DECORATION_DESCRIPTOR_SET, s, ..]) => {
                set.insert(*id, *s);
            }
            (OP_MEMBER_DECORATE, [ty, member, DECORATION_OFFSET, offset, ..]) => {
                member_offsets.insert((*ty, *member), *offset);
            }
            (OP_TYPE_POINTER, [id, storage, pointee, ..]) => {
                pointers.insert(*id, (*storage, *pointee));
            }
            (OP_TYPE_FORWARD_POINTER, [id, storage, ..]) => {
                pointers.entry(*id).or_insert((*storage, 0));
            }
            (OP_TYPE_STRUCT, [id, members @ ..]) => {
                structs.insert(*id, members.to_vec());
            }
            (OP_VARIABLE, [ty, _, STORAGE_PUSH_CONSTANT, ..]) => {
                push_block_pointer = Some(*ty);
            }
            (OP_VARIABLE, [ty, id, ..]) => variables.push((*id, *ty)),
            _ => {}
        }
        at += count;
    }
    let descriptor_bindings = variables
        .iter()
        .filter(|(id, _)| set.get(id) == Some(&0))
        .filter_map(|(id, _)| binding.get(id).copied())
        .collect();
    let mut interface = KernelInterface {
        descriptor_bindings,
        ..Default::default()
    };
    let block = push_block_pointer
        .and_then(|p| pointers.get(&p))
        .map(|&(_, pointee)| pointee);
    if let Some(members) = block.and_then(|b| structs.get(&b).map(|m| (b, m))) {
        let (block, member_types) = members;
        for (index, ty) in member_types.iter().enumerate() {
            let offset = *member_offsets.get(&(block, index as u32))?;
            let is_address = pointers
                .get(ty)
                .is_some_and(|&(storage, _)| storage == STORAGE_PHYSICAL_STORAGE_BUFFER);
            if is_address {
                interface.address_offsets.push(offset);
            } else {
                interface.value_offsets.push(offset);
            }
        }
        interface.address_offsets.sort_unstable();
        interface.value_offsets.sort_unstable();
    }
    Some(interface)
}

/// How a pipeline passes each of its `bindings` buffers.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct BufferPassing {
    /// Bindings pushed as descriptors.
    pub descriptors: Vec<u32>,
    /// (binding, push-constant offset) of the buffers passed by address.
    pub addresses: Vec<(u32, u32)>,
    /// Bytes of the push-constant range: the caller's values and the addresses.
    pub push_bytes: u32,
}

/// Matches a kernel's interface to `bindings` buffers and `value_bytes` bytes of the
/// caller's push constants, or says why they do not fit.
pub fn buffer_passing(
    interface: &KernelInterface,
    bindings: u32,
    value_bytes: u32,
) -> Result<BufferPassing, String> {
    let by_address = interface.address_offsets.len() as u32;
    if by_address > bindings {
        return Err(format!(
            "takes {bindings} buffers, but its push constants hold {by_address} buffer references"
        ));
    }
    if let Some(b) = interface
        .descriptor_bindings
        .iter()
        .find(|&&b| b < by_address)
    {
        return Err(format!(
            "declares binding {b} as a descriptor, but its {by_address} buffer references \
             take bindings 0..{by_address} by address"
        ));
    }
    if let Some(&first) = interface.address_offsets.first() {
        if first < value_bytes {
            return Err(format!(
                "has its first buffer reference at push-constant byte {first}, inside the \
                 {value_bytes} bytes of values given (references must end the block)"
            ));
        }
        if let Some(after) = interface.value_offsets.iter().find(|&&o| o >= first) {
            return Err(format!(
                "has a push-constant value at byte {after}, after a buffer reference \
                 (references must end the block)"
            ));
        }
    }
    let addresses: Vec<(u32, u32)> = (0..by_address)
        .zip(interface.address_offsets.iter().copied())
        .collect();
    let push_bytes = addresses
        .last()
        .map_or(value_bytes, |&(_, offset)| offset + 8);
    Ok(BufferPassing {
        descriptors: (by_address..bindings).collect(),
        addresses,
        push_bytes,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn interface(descriptors: &[u32], values: &[u32], addresses: &[u32]) -> KernelInterface {
        KernelInterface {
            descriptor_bindings: descriptors.iter().copied().collect(),
            address_offsets: addresses.to_vec(),
            value_offsets: values.to_vec(),
        }
    }

    #[test]
    fn the_first_bindings_go_by_address_the_rest_as_descriptors() {
        // Binding 3 unused by this variant: the optimiser dropped its descriptor.
        let i = interface(&[2, 4], &[0, 4], &[8, 16]);
        let p = buffer_passing(&i, 5, 8).unwrap();
        assert_eq!(p.addresses, vec![(0, 8), (1, 16)]);
        assert_eq!(p.descriptors, vec![2, 3, 4]);
        assert_eq!(p.push_bytes, 24);
    }

    #[test]
    fn descriptors_only_keep_the_callers_push_size() {
        let i = interface(&[0, 2], &[0], &[]);
        let p = buffer_passing(&i, 3, 4).unwrap();
        assert_eq!(p.descriptors, vec![0, 1, 2]);
        assert!(p.addresses.is_empty());
        assert_eq!(p.push_bytes, 4);
    }

    #[test]
    fn mismatches_are_explained() {
        let e = buffer_passing(&interface(&[], &[0], &[8, 16]), 1, 4).unwrap_err();
        assert!(
            e.contains("takes 1 buffers") && e.contains("2 buffer references"),
            "{e}"
        );
        let e = buffer_passing(&interface(&[0, 1], &[0], &[8]), 2, 4).unwrap_err();
        assert!(e.contains("binding 0 as a descriptor"), "{e}");
        let e = buffer_passing(&interface(&[], &[0], &[8]), 1, 12).unwrap_err();
        assert!(e.contains("byte 8"), "{e}");
        let e = buffer_passing(&interface(&[], &[0, 16], &[8]), 1, 8).unwrap_err();
        assert!(e.contains("byte 16, after"), "{e}");
    }

    #[test]
    fn malformed_spirv_is_refused() {
        assert_eq!(kernel_interface(&[]), None);
        assert_eq!(kernel_interface(&[0x0723_0203, 0, 0, 0, 0, 0]), None);
    }

    #[test]
    fn every_embedded_kernel_reflects() {
        for kernel in crate::shaders::ALL {
            let words = ash::util::read_spv(&mut std::io::Cursor::new(kernel.spirv)).unwrap();
            assert!(kernel_interface(&words).is_some(), "{}", kernel.name);
        }
    }
}
