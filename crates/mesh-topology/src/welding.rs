//! Exact-position welding: vertices whose positions are bit-for-bit equal (`-0.0 == +0.0`)
//! become one.

use glam::Vec3;

/// The result of exact-position welding.
#[derive(Debug, Clone, PartialEq)]
pub struct Weld {
    /// For each input vertex, its compact (welded) id.
    pub compact_of_input: Vec<u32>,
    /// For each compact id, the smallest input index of its weld group (its *name*).
    /// Strictly increasing.
    pub names: Vec<u32>,
    /// For each compact id, the position (identical for the whole group, up to the sign of zero).
    pub positions: Vec<Vec3>,
}

/// The bit pattern used as the weld key: `-0.0` is mapped to `+0.0`, everything else is kept.
#[inline]
pub(crate) fn weld_key(p: Vec3) -> [u32; 3] {
    // Adding +0.0 turns -0.0 into +0.0 and leaves every other finite value unchanged.
    [
        (p.x + 0.0).to_bits(),
        (p.y + 0.0).to_bits(),
        (p.z + 0.0).to_bits(),
    ]
}

/// Hash of a weld key: the top `bits` bits of a multiplicative mix of the three words.
#[inline]
pub(crate) fn weld_hash(k: [u32; 3], bits: u32) -> usize {
    let lo = u64::from(k[0]) | (u64::from(k[1]) << 32);
    let mut h = lo.wrapping_mul(0x9e37_79b9_7f4a_7c15)
        ^ u64::from(k[2]).wrapping_mul(0xc2b2_ae3d_27d4_eb4f);
    h ^= h >> 29;
    h = h.wrapping_mul(0x1656_67b1_9e37_79f9);
    (h >> (64 - bits)) as usize
}

/// Welds vertices whose positions are exactly equal (`-0.0 == +0.0`).
///
/// Each group is named by its smallest input index, and compact ids are numbered in ascending
/// order of names. The position of a group is the position of its named (first) vertex. Runs in
/// expected linear time (hashing with open addressing). Positions are expected to be finite
/// (see [`Mesh::validate`](crate::Mesh::validate)); NaN positions weld only with NaNs of the
/// identical bit pattern (their bits are kept).
#[must_use]
pub fn weld(positions: &[Vec3]) -> Weld {
    // Open addressing with linear probing in a table of at least twice the vertex count; a
    // slot holds a compact id (4 bytes), the key is compared against that group's key. This is
    // about half the memory traffic of a general hash map on 10^6-triangle meshes.
    let bits = (positions.len().max(8) * 2)
        .next_power_of_two()
        .trailing_zeros();
    let mask = (1usize << bits) - 1;
    let mut slots = vec![u32::MAX; 1 << bits];
    let mut keys: Vec<[u32; 3]> = Vec::new();
    let mut compact_of_input = Vec::with_capacity(positions.len());
    let mut names = Vec::new();
    let mut out_positions = Vec::new();
    for (i, &p) in positions.iter().enumerate() {
        let key = weld_key(p);
        let mut h = weld_hash(key, bits);
        let id = loop {
            let s = slots[h];
            if s == u32::MAX {
                let id = names.len() as u32;
                slots[h] = id;
                keys.push(key);
                names.push(i as u32);
                out_positions.push(p);
                break id;
            }
            if keys[s as usize] == key {
                break s;
            }
            h = (h + 1) & mask;
        };
        compact_of_input.push(id);
    }
    Weld {
        compact_of_input,
        names,
        positions: out_positions,
    }
}

/// True when no two of `positions` weld ([`weld`] would keep every vertex), found without
/// copying them; [`positions_distinct_by`] over the slice.
#[must_use]
pub fn positions_distinct(positions: &[Vec3]) -> bool {
    positions_distinct_by(positions.len(), |i| positions[i])
}

/// True when no two of the `count` positions `position(0..count)` weld, with nothing stored but
/// an open-addressing table of indices (4 bytes a slot, at least 1.5 times the count rounded up
/// to a power of two): `position` is called again to compare keys, so the positions may be
/// computed (moved by a transform, say) rather than held.
#[must_use]
pub fn positions_distinct_by(count: usize, position: impl Fn(usize) -> Vec3) -> bool {
    let bits = (count.max(8) * 3 / 2).next_power_of_two().trailing_zeros();
    let mask = (1usize << bits) - 1;
    let mut slots = vec![u32::MAX; 1 << bits];
    for i in 0..count {
        let key = weld_key(position(i));
        let mut h = weld_hash(key, bits);
        loop {
            let s = slots[h];
            if s == u32::MAX {
                slots[h] = i as u32;
                break;
            }
            if weld_key(position(s as usize)) == key {
                return false;
            }
            h = (h + 1) & mask;
        }
    }
    true
}
