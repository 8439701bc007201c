//! Exact-position welding: vertices whose positions are bit-for-bit equal (`-0.0 == +0.0`)
//! become one.

use glam::Vec3;
use rayon::prelude::*;
use std::sync::atomic::{AtomicU32, Ordering};

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
/// expected linear time, on all of rayon's threads when there are several (one pass on one
/// thread otherwise: the parallel steps do about twice the work); the result is the same either
/// way. Positions are expected to be finite (see [`Mesh::validate`](crate::Mesh::validate)); NaN
/// positions weld only with NaNs of the identical bit pattern (their bits are kept).
///
/// Memory besides the output: an index table of 4 bytes a slot, at least 1.5 times the vertex
/// count rounded up to a power of two, and 4 to 16 bytes a vertex of scratch.
#[must_use]
pub fn weld(positions: &[Vec3]) -> Weld {
    if positions.len() < PAR_MIN || rayon::current_num_threads() == 1 {
        weld_one_thread(positions)
    } else {
        weld_parallel(positions)
    }
}

/// [`weld`] of positions that arrive one at a time, as a triangle soup is read: each position
/// pushed ([`SoupWeld::push`]) comes back as its compact id, numbered and named exactly as
/// [`weld`] numbers and names the list of every position pushed, in order (a group is named by
/// its first input index, compact ids follow the names, a group's position is its first one's).
///
/// It holds only the distinct positions, their names and an index table (about 24 bytes a
/// distinct position), never the input list: a loader that turns corners into compact ids as it
/// reads them need not keep the soup (three positions a triangle).
///
/// ```
/// use glam::Vec3;
/// use shadowvol_mesh_topology::{weld, SoupWeld};
///
/// let soup = [Vec3::X, Vec3::Y, Vec3::ZERO, Vec3::new(-0.0, 0.0, 0.0), Vec3::Y, Vec3::Z];
/// let mut w = SoupWeld::new();
/// let ids: Vec<u32> = soup.iter().map(|&p| w.push(p)).collect();
/// let whole = weld(&soup);
/// assert_eq!(ids, whole.compact_of_input);
/// assert_eq!((w.names(), w.positions()), (&whole.names[..], &whole.positions[..]));
/// ```
#[derive(Debug, Clone, Default)]
pub struct SoupWeld {
    /// Open-addressing index table of compact ids (`u32::MAX` empty); empty before the first
    /// push.
    slots: Vec<u32>,
    names: Vec<u32>,
    positions: Vec<Vec3>,
    pushed: u64,
}

impl SoupWeld {
    /// An empty weld.
    #[must_use]
    pub fn new() -> Self {
        Self::default()
    }

    /// An empty weld whose index table holds `n` distinct positions without growing (the
    /// table [`weld`] sizes for `n` inputs: at least 1.5 `n` slots).
    #[must_use]
    pub fn with_capacity(n: usize) -> Self {
        Self {
            slots: vec![u32::MAX; 1 << table_bits(n)],
            names: Vec::with_capacity(n),
            positions: Vec::with_capacity(n),
            pushed: 0,
        }
    }

    /// Welds the next input position (input index [`SoupWeld::pushed`]) and returns its compact
    /// id.
    ///
    /// # Panics
    /// Panics past `u32::MAX` input positions (a loader refuses such inputs first).
    pub fn push(&mut self, p: Vec3) -> u32 {
        let name = u32::try_from(self.pushed).expect("at most u32::MAX input positions");
        self.pushed += 1;
        // Grow at a load of 2/3: probes stay short.
        if 3 * (self.names.len() + 1) > 2 * self.slots.len() {
            self.grow();
        }
        let key = weld_key(p);
        let bits = self.slots.len().trailing_zeros();
        let mask = self.slots.len() - 1;
        let mut h = weld_hash(key, bits);
        loop {
            let s = self.slots[h];
            if s == u32::MAX {
                let id = self.names.len() as u32;
                self.slots[h] = id;
                self.names.push(name);
                self.positions.push(p);
                return id;
            }
            if weld_key(self.positions[s as usize]) == key {
                return s;
            }
            h = (h + 1) & mask;
        }
    }

    /// Doubles the index table (at least 16 slots) and re-inserts every group.
    fn grow(&mut self) {
        let n = (2 * self.slots.len()).max(16);
        let bits = n.trailing_zeros();
        let mut slots = vec![u32::MAX; n];
        for (id, &p) in self.positions.iter().enumerate() {
            let mut h = weld_hash(weld_key(p), bits);
            while slots[h] != u32::MAX {
                h = (h + 1) & (n - 1);
            }
            slots[h] = id as u32;
        }
        self.slots = slots;
    }

    /// Input positions pushed so far.
    #[must_use]
    pub fn pushed(&self) -> u64 {
        self.pushed
    }

    /// Each compact id's name: the input index of its group's first position.
    #[must_use]
    pub fn names(&self) -> &[u32] {
        &self.names
    }

    /// Each compact id's position.
    #[must_use]
    pub fn positions(&self) -> &[Vec3] {
        &self.positions
    }

    /// The names and positions, the index table freed.
    #[must_use]
    pub fn into_parts(self) -> (Vec<u32>, Vec<Vec3>) {
        (self.names, self.positions)
    }
}

/// Index-table bits for `n` vertices: at least 1.5 `n` slots, a power of two.
fn table_bits(n: usize) -> u32 {
    (n.max(8) * 3 / 2).next_power_of_two().trailing_zeros()
}

/// [`weld`] in one pass: a [`SoupWeld`] sized for every input, so its table never grows.
fn weld_one_thread(positions: &[Vec3]) -> Weld {
    let mut w = SoupWeld::with_capacity(positions.len());
    let compact_of_input = positions.iter().map(|&p| w.push(p)).collect();
    let (names, positions) = w.into_parts();
    Weld {
        compact_of_input,
        names,
        positions,
    }
}

/// [`weld`] on rayon's threads, in four parallel steps over the vertices.
fn weld_parallel(positions: &[Vec3]) -> Weld {
    let n = positions.len();
    let bits = table_bits(n);
    let table = GroupTable::new(bits);
    // 1. Every vertex into the table, where its group's slot ends up holding the group's
    //    smallest index; each vertex's slot is kept (it becomes its compact id in step 4).
    let mut compact_of_input: Vec<u32> = positions
        .par_iter()
        .enumerate()
        .with_min_len(PAR_MIN)
        .map(|(i, &p)| table.insert(positions, i as u32, weld_key(p)))
        .collect();
    // 2. The firsts (a vertex whose group's slot holds it), counted per chunk of vertices.
    let chunk = n.div_ceil(rayon::current_num_threads() * 8).max(PAR_MIN);
    let first: Vec<bool> = compact_of_input
        .par_iter()
        .enumerate()
        .with_min_len(PAR_MIN)
        .map(|(i, &slot)| table.get(slot) == i as u32)
        .collect();
    let counts: Vec<usize> = first
        .par_chunks(chunk)
        .map(|c| c.iter().filter(|&&f| f).count())
        .collect();
    // 3. Each chunk numbers its own firsts (ids in order of names), writes their names and
    //    positions, and puts each id in its group's slot (no slot is read for step 2 any more).
    let welded: usize = counts.iter().sum();
    let mut names = vec![0u32; welded];
    let mut out_positions = vec![Vec3::ZERO; welded];
    let mut first_ids = Vec::with_capacity(counts.len());
    let mut next = 0u32;
    for &k in &counts {
        first_ids.push(next);
        next += k as u32;
    }
    let slot_of = &compact_of_input;
    first
        .par_chunks(chunk)
        .zip(split_by(&mut names, counts.iter().copied()))
        .zip(split_by(&mut out_positions, counts.iter().copied()))
        .zip(&first_ids)
        .enumerate()
        .for_each(|(c, (((firsts, nm), ps), &first_id))| {
            let found = firsts.iter().enumerate().filter(|(_, &f)| f);
            for (k, (j, _)) in found.enumerate() {
                let i = c * chunk + j;
                nm[k] = i as u32;
                ps[k] = positions[i];
                table.set(slot_of[i], first_id + k as u32);
            }
        });
    drop(first);
    // 4. Every vertex's compact id, from its group's slot.
    compact_of_input
        .par_iter_mut()
        .with_min_len(PAR_MIN)
        .for_each(|s| *s = table.get(*s));
    Weld {
        compact_of_input,
        names,
        positions: out_positions,
    }
}

/// `v` cut into consecutive parts of the given lengths (which must add up to at most its
/// length).
pub(crate) fn split_by<T>(v: &mut [T], lens: impl Iterator<Item = usize>) -> Vec<&mut [T]> {
    let mut rest = v;
    lens.map(|n| {
        let (part, r) = std::mem::take(&mut rest).split_at_mut(n);
        rest = r;
        part
    })
    .collect()
}

/// Vertices below which a parallel step runs on one thread (rayon's splitting costs more).
const PAR_MIN: usize = 1 << 14;

/// The weld's open-addressing table with linear probing: a slot holds an input index (a
/// group's smallest so far) while groups are found, a compact id once they are numbered. Keys
/// are not stored; they are read from the positions.
struct GroupTable {
    slots: Vec<AtomicU32>,
    bits: u32,
}

impl GroupTable {
    const EMPTY: u32 = u32::MAX;

    fn new(bits: u32) -> Self {
        Self {
            slots: (0..1usize << bits)
                .map(|_| AtomicU32::new(Self::EMPTY))
                .collect(),
            bits,
        }
    }

    fn get(&self, slot: u32) -> u32 {
        self.slots[slot as usize].load(Ordering::Relaxed)
    }

    fn set(&self, slot: u32, value: u32) {
        self.slots[slot as usize].store(value, Ordering::Relaxed);
    }

    /// Puts vertex `i` (key `key`) in its group's slot and returns the slot. The slot keeps the
    /// group's smallest index: an empty slot is claimed with a compare-exchange, an equal key's
    /// slot takes the minimum, so the outcome is the same in any order.
    fn insert(&self, positions: &[Vec3], i: u32, key: [u32; 3]) -> u32 {
        let mask = (1usize << self.bits) - 1;
        let mut h = weld_hash(key, self.bits);
        loop {
            let slot = &self.slots[h];
            let s = slot.load(Ordering::Relaxed);
            if s == Self::EMPTY {
                match slot.compare_exchange(Self::EMPTY, i, Ordering::Relaxed, Ordering::Relaxed) {
                    Ok(_) => return h as u32,
                    Err(_) => continue, // claimed meanwhile: look at this slot again
                }
            }
            // Every index a slot ever holds has the same key, so a stale `s` compares the same.
            if weld_key(positions[s as usize]) == key {
                slot.fetch_min(i, Ordering::Relaxed);
                return h as u32;
            }
            h = (h + 1) & mask;
        }
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
