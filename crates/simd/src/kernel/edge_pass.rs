//! The edge pass of `robust`, `ordered` and `exact`: `m(e) = Σ sign(t) · parity(e, t)` over
//! the triangles of each edge, from the triangle pass's signs. Each (edge, OV) pair's triangle
//! slot `s` and parity come from its reference `4 s + r` (odd for `r = 1`). Scalar at the `wide`
//! level; with AVX2, 8 edges per vector ([`edge_sums_avx2`]).
//!
//! With the shared bytes of the shared triangle pass ([`PackedSigns::shared`]), an edge whose
//! triangles are all shared by the box of the lights has one multiplicity for every light: it is
//! computed once, and written to every light's row where it is not 0 (the rows start all 0).

use super::signs::{pack_sign, signed, NOT_SHARED, PACK};
use super::{push_bits, EdgeOut};
use crate::dispatch::Pass;
use crate::lanes::Level;
use crate::layout::{ref_odd, ref_slot, FastRefs, Geometry, LANES};
use std::ops::Range;

/// The triangle signs an edge pass reads for one object: light `l`'s sign of the object's
/// triangle slot `t` is [`pack_sign`]`(all[bases[l / PACK] + t], lights, l)`.
#[derive(Clone, Copy)]
pub(crate) struct PackedSigns<'a> {
    /// The signs of every object, pack after pack of lights.
    pub all: &'a [i8],
    /// Per pack of lights, the index in `all` of the object's slot 0.
    pub bases: &'a [usize],
    /// In exact mode with the lights' box: the object's shared bytes from its slot 0 (each
    /// triangle's sign for the whole box, or [`NOT_SHARED`]). Then every row starts all 0, and
    /// an edge whose triangles are all shared is written only where its multiplicity is not 0.
    pub shared: Option<&'a [i8]>,
}

/// The edge pass over the blocks `blocks` of one object: `out.rows[l]` receives the range's
/// multiplicities for light `l`, `out.sil[l]` collects `edge_base + e` where `m != 0`.
pub(crate) struct EdgeSums<'a, 'r, G> {
    /// The object's layout.
    pub lay: &'a G,
    /// Blocks of 8 edges.
    pub blocks: Range<usize>,
    /// The object's triangle signs.
    pub signs: PackedSigns<'a>,
    /// Where the results go.
    pub out: EdgeOut<'a, 'r>,
}

impl<G: Geometry> Pass for EdgeSums<'_, '_, G> {
    type Out = ();
    #[inline(always)]
    fn run<Lv: Level>(self) {
        edge_sums(self);
    }
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    unsafe fn run_avx2(self) {
        // SAFETY: AVX2 is present (the contract of `run_avx2`).
        unsafe { edge_sums_avx2(self) }
    }
}

impl<G: Geometry> EdgeSums<'_, '_, G> {
    /// Asserts what the kernels rely on (one sign base per pack of lights, each followed by the
    /// object's `tri_count` slots) and returns the range's first edge, where `out.rows` start.
    #[inline(always)]
    fn check(&self) -> usize {
        let PackedSigns { all, bases, shared } = self.signs;
        // Every reference names a triangle slot < tri_count (`Layout::build`).
        assert!(bases.iter().all(|&b| b + self.lay.tri_count() <= all.len()));
        assert!(shared.is_none_or(|s| self.lay.tri_count() <= s.len()));
        assert!(bases.len() == self.out.rows.len().div_ceil(PACK));
        self.blocks.start * LANES
    }
}

/// Multiplicities of the edges in `blocks` from the triangle signs, scalar (see [`EdgeSums`]).
///
/// # Panics
/// If a slice is shorter than described.
fn edge_sums<G: Geometry>(pass: EdgeSums<G>) {
    let e_start = pass.check();
    let (lay, blocks, ps, mut out) = (pass.lay, pass.blocks, pass.signs, pass.out);
    let (signs, bases, edge_base) = (ps.all, ps.bases, out.edge_base);
    let nl = out.rows.len();
    for blk in blocks {
        let e0 = blk * LANES;
        if lay.block_fast(blk) {
            // Block-outer, light-inner: the block's OV references are read once.
            let [first, second] = *lay.fast_refs(blk);
            if let Some(sh) = ps.shared {
                if let Some(m) = shared_block(&[first, second], sh) {
                    let nz = m
                        .iter()
                        .enumerate()
                        .fold(0u32, |bits, (i, &x)| bits | u32::from(x != 0) << i);
                    write_nonzero(&m, nz, e0 - e_start, e0, &mut out);
                    continue;
                }
            }
            for (l, row) in out.rows.iter_mut().enumerate() {
                let base = bases[l / PACK];
                let s = &signs[base..base + lay.tri_count()];
                // The last block may be partial (the references are padded): `dst` holds the
                // real edges only.
                let end = (e0 - e_start + LANES).min(row.len());
                let dst = &mut row[e0 - e_start..end];
                let mut any = 0;
                for (i, d) in dst.iter_mut().enumerate() {
                    let sign = |r: u32| signed(light_sign(&ps, s, r, nl, l), ref_odd(r));
                    let m = sign(first[i]) + sign(second[i]);
                    *d = m;
                    any |= m;
                }
                if any != 0 {
                    for (i, &m) in dst.iter().enumerate() {
                        if m != 0 {
                            out.sil[l].push((edge_base + e0 + i) as u32);
                        }
                    }
                }
            }
        } else {
            edge_sums_general(lay, e0, e_start, &ps, &mut out);
        }
    }
}

/// The general (CSR) path of [`edge_sums`] for the block starting at edge `e0`; `out.rows`
/// start at edge `e_start`.
#[inline(always)]
fn edge_sums_general<G: Geometry>(
    lay: &G,
    e0: usize,
    e_start: usize,
    ps: &PackedSigns,
    out: &mut EdgeOut,
) {
    let nl = out.rows.len();
    for e in e0..(e0 + LANES).min(lay.edge_count()) {
        let refs = lay.general_refs(e);
        if let Some(sh) = ps.shared {
            if refs.iter().all(|&r| sh[ref_slot(r)] != NOT_SHARED) {
                let m: i32 = refs
                    .iter()
                    .map(|&r| signed(sh[ref_slot(r)], ref_odd(r)))
                    .sum();
                for (row, sil) in out.rows.iter_mut().zip(out.sil.iter_mut()) {
                    row[e - e_start] = m;
                    if m != 0 {
                        sil.push((out.edge_base + e) as u32);
                    }
                }
                continue;
            }
        }
        for (l, row) in out.rows.iter_mut().enumerate() {
            let base = ps.bases[l / PACK];
            let s = &ps.all[base..];
            let m: i32 = refs
                .iter()
                .map(|&r| signed(light_sign(ps, s, r, nl, l), ref_odd(r)))
                .sum();
            row[e - e_start] = m;
            if m != 0 {
                out.sil[l].push((out.edge_base + e) as u32);
            }
        }
    }
}

/// Light `l`'s sign (of `nl`) of the triangle of reference `r`: its shared sign when the box
/// shares it (`ps.shared`), else from its pack byte in `s` (the light's pack, from the object's
/// slot 0).
#[inline(always)]
fn light_sign(ps: &PackedSigns, s: &[i8], r: u32, nl: usize, l: usize) -> i8 {
    let t = ref_slot(r);
    match ps.shared.map(|sh| sh[t]) {
        Some(x) if x != NOT_SHARED => x,
        _ => pack_sign(s[t], nl, l),
    }
}

/// The multiplicities of a fast block whose triangles are all shared (`sh`: the object's shared
/// bytes), or `None` when one is not.
#[inline(always)]
fn shared_block(refs: &FastRefs, sh: &[i8]) -> Option<[i32; LANES]> {
    let mut m = [0i32; LANES];
    for (i, m) in m.iter_mut().enumerate() {
        let (r1, r2) = (refs[0][i], refs[1][i]);
        let (s1, s2) = (sh[ref_slot(r1)], sh[ref_slot(r2)]);
        if s1 == NOT_SHARED || s2 == NOT_SHARED {
            return None;
        }
        *m = signed(s1, ref_odd(r1)) + signed(s2, ref_odd(r2));
    }
    Some(m)
}

/// Writes the non-zero lanes `nz` of one block's multiplicities `m` (edges `e0 ..`, at `at`
/// in each row; fewer where the rows end) to every light's row, and those edges to every
/// light's list. With shared triangles the rows start all 0 (see [`PackedSigns::shared`]), so
/// the zero lanes need no store.
#[inline(always)]
fn write_nonzero(m: &[i32; LANES], nz: u32, at: usize, e0: usize, out: &mut EdgeOut) {
    let real = (out.rows[0].len() - at).min(LANES);
    let nz = nz & ((1u32 << real) - 1);
    if nz == 0 {
        return;
    }
    for (row, sil) in out.rows.iter_mut().zip(out.sil.iter_mut()) {
        let mut bits = nz;
        while bits != 0 {
            let i = bits.trailing_zeros() as usize;
            bits &= bits - 1;
            row[at + i] = m[i];
        }
        push_bits(sil, nz, out.edge_base + e0);
    }
}

/// The sign bytes (sign-extended to 32-bit lanes) of the triangles of the block's first OV
/// references (`refs[0][i]`, lane `i`) and of its second (`refs[1][i]`) in the pack at `sp`,
/// and their parity masks (all ones for odd parity, else 0). The bytes take scalar loads, which
/// are faster than `vpgatherdd` on Zen 3 (docs/PERFORMANCE.md); the parities are computed in
/// lanes.
///
/// # Safety
/// AVX2 present (the caller is compiled with it); every reference's triangle `r >> 2` is a slot
/// inside the pack at `sp`.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
unsafe fn sign_bytes_of_block(sp: *const i8, refs: &FastRefs) -> [std::arch::x86_64::__m256i; 4] {
    use std::arch::x86_64::*;
    // SAFETY: every `r >> 2` is inside the pack at `sp` (the caller's contract); AVX2 present.
    unsafe {
        let signs = |r: &[u32; LANES]| {
            let ld = |i: usize| -> i32 { i32::from(*sp.add((r[i] >> 2) as usize)) };
            _mm256_setr_epi32(ld(0), ld(1), ld(2), ld(3), ld(4), ld(5), ld(6), ld(7))
        };
        let (three, one) = (_mm256_set1_epi32(3), _mm256_set1_epi32(1));
        // Rank 1: odd parity.
        let odd = |r: &[u32; LANES]| {
            let r = _mm256_loadu_si256(r.as_ptr().cast());
            _mm256_cmpeq_epi32(_mm256_and_si256(r, three), one)
        };
        [
            signs(&refs[0]),
            signs(&refs[1]),
            odd(&refs[0]),
            odd(&refs[1]),
        ]
    }
}

/// Stores the first `dst.len()` (< 8: the padded last block of an object) lanes of `m` and
/// returns the mask of those lanes.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
fn store_part_epi32(m: std::arch::x86_64::__m256i, dst: &mut [i32]) -> u32 {
    let mut lanes = [0i32; LANES];
    // SAFETY: `lanes` is 32 writable bytes; unaligned store; AVX2 present (the callers are
    // compiled with it).
    unsafe { std::arch::x86_64::_mm256_storeu_si256(lanes.as_mut_ptr().cast(), m) };
    let n = dst.len().min(LANES);
    dst[..n].copy_from_slice(&lanes[..n]);
    (1u32 << n) - 1
}

/// [`edge_sums`] with 8 edges per AVX2 vector: per block and pack of four lights, 16 scalar
/// byte loads fetch the signs of both triangles of 8 edges for all four lights (see [`PACK`]).
/// Identical results.
///
/// # Safety
/// The CPU must support AVX2.
///
/// # Panics
/// If a slice is shorter than described.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn edge_sums_avx2<G: Geometry>(pass: EdgeSums<G>) {
    use std::arch::x86_64::*;
    let e_start = pass.check();
    let (lay, blocks, ps, mut out) = (pass.lay, pass.blocks, pass.signs, pass.out);
    let (signs, bases, edge_base) = (ps.all, ps.bases, out.edge_base);
    if let ([_], [out0], [sil0]) = (bases, &mut *out.rows, &mut *out.sil) {
        // SAFETY: AVX2 is enabled here, as the callee needs.
        unsafe { one_light_avx2(lay, blocks, &ps, out0, sil0, edge_base) };
        _mm_sfence();
        return;
    }
    for blk in blocks {
        let e0 = blk * LANES;
        if lay.block_fast(blk) {
            let refs = lay.fast_refs(blk);
            let refs: &FastRefs = &refs;
            // The shared bytes of the block's triangles.
            // SAFETY: AVX2 is enabled here; every reference's triangle is < tri_count <=
            // sh.len() (`EdgeSums::check`).
            let shared = ps
                .shared
                .map(|sh| unsafe { sign_bytes_of_block(sh.as_ptr(), refs) });
            if let Some(g) = &shared {
                // SAFETY: AVX2 is enabled here.
                if let Some((m, nz)) = unsafe { shared_block_avx2(g) } {
                    if nz != 0 {
                        let mut lanes = [0i32; LANES];
                        // SAFETY: `lanes` is 32 writable bytes; unaligned store.
                        unsafe { _mm256_storeu_si256(lanes.as_mut_ptr().cast(), m) };
                        write_nonzero(&lanes, nz, e0 - e_start, e0, &mut out);
                    }
                    continue;
                }
            }
            for (pack, &base) in bases.iter().enumerate() {
                // The 16 sign bytes of the block's triangles, as in the one-light loop.
                // SAFETY: every reference's triangle is < tri_count (`Layout::build`), and
                // base + tri_count <= signs.len() (asserted above).
                let [g1, g2, k1, k2] =
                    unsafe { sign_bytes_of_block(signs.as_ptr().add(base), refs) };
                // A shared triangle's pack byte was not written: its shared sign, for every
                // light of the pack.
                let (g1, g2) = match &shared {
                    // SAFETY: AVX2 is enabled here.
                    Some([s1, s2, _, _]) => unsafe { (with_shared(g1, *s1), with_shared(g2, *s2)) },
                    None => (g1, g2),
                };
                // Each byte holds four lights' signs as bits (`PACK`; the loads sign-extended
                // it, the shuffle reads byte 0 only). Copy it to the four
                // bytes of its lane, and make byte `j` the sign of light `4 pack + j`: `+1`
                // where bit `j` is set, `-1` where bit `4 + j` is.
                let bcast = _mm256_setr_epi8(
                    0, 0, 0, 0, 4, 4, 4, 4, 8, 8, 8, 8, 12, 12, 12, 12, 0, 0, 0, 0, 4, 4, 4, 4, 8,
                    8, 8, 8, 12, 12, 12, 12,
                );
                let pos_bit = _mm256_set1_epi32(0x0804_0201);
                let neg_bit = _mm256_set1_epi32(0x8040_2010_u32 as i32);
                let (x1, x2) = (
                    _mm256_shuffle_epi8(g1, bcast),
                    _mm256_shuffle_epi8(g2, bcast),
                );
                // -1 where the bit is set, so `neg - pos` is the sign.
                let sign = |x: __m256i| {
                    _mm256_sub_epi8(
                        _mm256_cmpeq_epi8(_mm256_and_si256(x, neg_bit), neg_bit),
                        _mm256_cmpeq_epi8(_mm256_and_si256(x, pos_bit), pos_bit),
                    )
                };
                let (g1, g2) = (sign(x1), sign(x2));
                // Negate every byte where the parity is odd (`k` is 0 or all ones in each
                // 32-bit lane, so `(g ^ k) - k` per byte) and add the two triangles: byte `j`
                // of lane `i` is then `m` of edge `e0 + i` for light `4 pack + j`, in
                // `-2 ..= 2`.
                let s1 = _mm256_sub_epi8(_mm256_xor_si256(g1, k1), k1);
                let s2 = _mm256_sub_epi8(_mm256_xor_si256(g2, k2), k2);
                let m = _mm256_add_epi8(s1, s2);
                let lights = (out.rows.len() - pack * PACK).min(PACK);
                // Bit `4 i + j` set where that byte is non-zero, for this pack's lights only
                // (the bytes of absent lights are not read).
                let zero = _mm256_movemask_epi8(_mm256_cmpeq_epi8(m, _mm256_setzero_si256()));
                let nz = !(zero as u32) & (0x1111_1111u32 * ((1 << lights) - 1));
                // Byte `j` of each lane, sign-extended to i32.
                let rows = [
                    _mm256_srai_epi32::<24>(_mm256_slli_epi32::<24>(m)),
                    _mm256_srai_epi32::<24>(_mm256_slli_epi32::<16>(m)),
                    _mm256_srai_epi32::<24>(_mm256_slli_epi32::<8>(m)),
                    _mm256_srai_epi32::<24>(m),
                ];
                let pack_out = &mut out.rows[pack * PACK..pack * PACK + lights];
                let mut keep = 0xFF;
                for (row, dst) in rows.iter().zip(pack_out.iter_mut()) {
                    let dst = &mut dst[e0 - e_start..];
                    if dst.len() >= LANES {
                        // SAFETY: `dst` holds 8 i32; unaligned store. (Not a streaming store:
                        // with several lights' rows, half a cache line each per block, those
                        // thrash the write-combining buffers.)
                        unsafe { _mm256_storeu_si256(dst.as_mut_ptr().cast(), *row) };
                    } else {
                        keep = store_part_epi32(*row, dst);
                    }
                }
                if nz != 0 {
                    // Silhouette edges in this block (rare): the lanes of each light.
                    for (j, row) in rows.iter().enumerate().take(lights) {
                        let z = _mm256_movemask_ps(_mm256_castsi256_ps(_mm256_cmpeq_epi32(
                            *row,
                            _mm256_setzero_si256(),
                        ))) as u32;
                        push_bits(&mut out.sil[pack * PACK + j], !z & keep, edge_base + e0);
                    }
                }
            }
        } else {
            edge_sums_general(lay, e0, e_start, &ps, &mut out);
        }
    }
    // The streaming stores above are weakly ordered: make them visible before the caller
    // (another thread, after rayon's join) reads the output.
    _mm_sfence();
}

/// [`shared_block`] in AVX2 lanes, from the block's shared bytes as [`sign_bytes_of_block`]
/// gathers them: when every triangle of the fast block is shared, its multiplicities and the
/// bits of its non-zero lanes.
///
/// # Safety
/// The CPU must support AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
unsafe fn shared_block_avx2(
    [g1, g2, k1, k2]: &[std::arch::x86_64::__m256i; 4],
) -> Option<(std::arch::x86_64::__m256i, u32)> {
    use std::arch::x86_64::*;
    let mark = _mm256_set1_epi32(i32::from(NOT_SHARED));
    let cut = _mm256_or_si256(_mm256_cmpeq_epi32(*g1, mark), _mm256_cmpeq_epi32(*g2, mark));
    if _mm256_movemask_epi8(cut) != 0 {
        return None;
    }
    let s1 = _mm256_sub_epi32(_mm256_xor_si256(*g1, *k1), *k1);
    let s2 = _mm256_sub_epi32(_mm256_xor_si256(*g2, *k2), *k2);
    let m = _mm256_add_epi32(s1, s2);
    let zero = _mm256_movemask_ps(_mm256_castsi256_ps(_mm256_cmpeq_epi32(
        m,
        _mm256_setzero_si256(),
    ))) as u32;
    Some((m, !zero & 0xFF))
}

/// The pack bytes `g` (one per 32-bit lane, sign-extended) with each shared triangle's byte
/// (its shared byte in `s` is not [`NOT_SHARED`]) made from its shared sign: `0x0F` for `+1`,
/// `0xF0` for `-1`, 0 for 0 (every light of the pack; the bits of absent lights are not read).
///
/// # Safety
/// The CPU must support AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
unsafe fn with_shared(
    g: std::arch::x86_64::__m256i,
    s: std::arch::x86_64::__m256i,
) -> std::arch::x86_64::__m256i {
    use std::arch::x86_64::*;
    let pos = _mm256_and_si256(
        _mm256_cmpeq_epi32(s, _mm256_set1_epi32(1)),
        _mm256_set1_epi32(0x0F),
    );
    let neg = _mm256_and_si256(
        _mm256_cmpeq_epi32(s, _mm256_set1_epi32(-1)),
        _mm256_set1_epi32(0xF0),
    );
    let cut = _mm256_cmpeq_epi32(s, _mm256_set1_epi32(i32::from(NOT_SHARED)));
    _mm256_blendv_epi8(_mm256_or_si256(pos, neg), g, cut)
}

/// The one-light case of [`edge_sums_avx2`] (the common case): its loop without the pack and
/// lane loops. The light's signs are at `ps.all[ps.bases[0]..]`; the multiplicities of the
/// edges of `blocks` go to `out0` with streaming stores (the caller fences them), the
/// silhouette edges to `sil0`.
///
/// # Safety
/// The CPU must support AVX2; the slices are as [`EdgeSums::check`] asserts.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
unsafe fn one_light_avx2<G: Geometry>(
    lay: &G,
    blocks: Range<usize>,
    ps: &PackedSigns,
    out0: &mut [i32],
    sil0: &mut Vec<u32>,
    edge_base: usize,
) {
    use std::arch::x86_64::*;
    let (signs, base, e_start) = (ps.all, ps.bases[0], blocks.start * LANES);
    for blk in blocks {
        let e0 = blk * LANES;
        if !lay.block_fast(blk) {
            let mut one = [&mut *out0];
            let mut rest = EdgeOut {
                rows: &mut one,
                sil: std::slice::from_mut(sil0),
                edge_base,
            };
            edge_sums_general(lay, e0, e_start, ps, &mut rest);
            continue;
        }
        let refs = lay.fast_refs(blk);
        let refs: &FastRefs = &refs;
        // SAFETY: every reference's triangle is < tri_count (`Layout::build`), and base +
        // tri_count <= signs.len() (`EdgeSums::check`).
        let [g1, g2, k1, k2] = unsafe { sign_bytes_of_block(signs.as_ptr().add(base), refs) };
        // The loads sign-extended each byte already.
        let s1 = _mm256_sub_epi32(_mm256_xor_si256(g1, k1), k1);
        let s2 = _mm256_sub_epi32(_mm256_xor_si256(g2, k2), k2);
        let m = _mm256_add_epi32(s1, s2);
        let dst = &mut out0[e0 - e_start..];
        let keep = if dst.len() >= LANES {
            // SAFETY: `dst` holds 8 i32 (written once, not read back here).
            unsafe { crate::lanes::stream_i32x8(dst.as_mut_ptr().cast(), m) };
            0xFF
        } else {
            store_part_epi32(m, dst)
        };
        let zero = _mm256_movemask_ps(_mm256_castsi256_ps(_mm256_cmpeq_epi32(
            m,
            _mm256_setzero_si256(),
        ))) as u32;
        push_bits(sil0, !zero & keep, edge_base + e0);
    }
}
