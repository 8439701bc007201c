//! How the triangle pass stores a block's signs and the edge pass reads them.
//!
//! Each pack of up to [`PACK`] lights holds one byte per triangle slot: with one light the sign
//! as an `i8`, with several the signs of the pack's lights as bits. The triangle pass builds a
//! block's bytes from lane masks ([`write_one`], [`write_pack`], [`set_sign_bits`]); the edge
//! pass decodes them ([`pack_sign`]) and applies the permutation parity ([`signed`]).
//!
//! A slot is a triangle of the table, in the table's order: the OV corner `3 t + j` of an
//! (edge, OV) pair names its slot `t`.

use crate::lanes::or_sign_mask_bits;
use crate::layout::LANES;

/// Lights per sign pack. Every pack holds one byte per triangle slot. With one light the byte
/// is the sign as an `i8` (`1`, `0`, `-1`). With several, the byte of slot `t` in pack `l / 4`
/// holds light `l`'s sign as bits: bit `l % 4` set for `+1`, bit `4 + l % 4` set for `-1`
/// (neither for 0), so one byte load serves four lights and the array is as small as with one
/// light (see [`pack_sign`]).
pub(crate) const PACK: usize = 4;

/// The shared byte of a triangle whose plane cuts the box of the call's lights (the shared
/// triangle pass, `super::shared`): its signs are per light. A shared triangle's byte is its
/// sign (`1`, `0`, `-1`).
pub(crate) const NOT_SHARED: i8 = 0x40;

/// Light `l`'s sign from its slot byte `b` in a call with `lights` lights (see [`PACK`]).
#[inline(always)]
pub(super) fn pack_sign(b: i8, lights: usize, l: usize) -> i8 {
    if lights == 1 {
        b
    } else {
        let (b, k) = (b as u8, l % PACK);
        (b >> k & 1) as i8 - (b >> (4 + k) & 1) as i8
    }
}

/// Byte `i` = 1 where bit `i` of the index is set (sign bytes of positive lanes).
const POS_BYTES: [u64; 256] = {
    let mut t = [0u64; 256];
    let mut i = 0;
    while i < 256 {
        let mut b = 0;
        while b < 8 {
            if i & (1 << b) != 0 {
                t[i] |= 1 << (8 * b);
            }
            b += 1;
        }
        i += 1;
    }
    t
};

/// Per-lane `i8` signs from disjoint positive / negative bit masks.
#[inline(always)]
fn sign_bytes(pos: u32, neg: u32) -> [u8; 8] {
    // Negative lanes become 0xFF (= -1i8) = 0xFF * 1.
    (POS_BYTES[(pos & 0xFF) as usize] | (POS_BYTES[(neg & 0xFF) as usize] * 0xFF)).to_le_bytes()
}

/// Sets the bits of light `k` in the several-light sign bytes `acc[i]`, for the lanes `i` in
/// `lanes`, to the sign given by the disjoint bit masks `pos` / `neg` (bit `k` for `+1`, bit
/// `4 + k` for `-1`, neither for 0).
#[inline(always)]
pub(super) fn set_sign_bits(acc: &mut [u32; LANES], k: usize, lanes: u32, pos: u32, neg: u32) {
    for (i, a) in acc.iter_mut().enumerate() {
        if lanes >> i & 1 == 1 {
            *a &= !(0x11 << k);
        }
    }
    or_sign_mask_bits(acc, pos & lanes, neg & lanes, k as u32);
}

/// Writes one light's signs of the block at slot `dst` (one light: `i8` signs, one byte per
/// slot).
#[inline(always)]
pub(super) fn write_one(out: &mut [&mut [i8]], dst: usize, pos: u32, neg: u32) {
    for (d, b) in out[0][dst..dst + LANES]
        .iter_mut()
        .zip(sign_bytes(pos, neg))
    {
        *d = b as i8;
    }
}

/// Writes the several-light sign bytes `acc` (byte of lane `i` = `acc[i]`, see [`PACK`]) of
/// the block at slot `dst` into pack `pack`; lanes outside `valid` (padding) get 0.
#[inline(always)]
pub(super) fn write_pack(
    out: &mut [&mut [i8]],
    pack: usize,
    dst: usize,
    acc: &[u32; LANES],
    valid: u32,
) {
    for (i, (d, a)) in out[pack][dst..dst + LANES].iter_mut().zip(acc).enumerate() {
        *d = if valid >> i & 1 == 1 {
            *a as u8 as i8
        } else {
            0
        };
    }
}

/// `s`, negated where the (edge, OV) pair has odd parity.
#[inline(always)]
pub(super) fn signed(s: i8, odd: bool) -> i32 {
    let k = i32::from(odd); // 1 for odd parity
    (i32::from(s) ^ -k) + k
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn set_sign_bits_replaces_one_light_of_the_chosen_lanes() {
        // Light 2 (bits 2 and 6) of lanes 1, 2 and 6: lane 1 negative, lane 2 zero, lane 6
        // positive; the positive bit of lane 0 is outside `lanes` and ignored. The other bits
        // are kept.
        let mut acc = [0xFFu32; LANES];
        set_sign_bits(&mut acc, 2, 0b0100_0110, 0b0100_0001, 0b0000_0010);
        let mut want = [0xFFu32; LANES];
        want[1] = 0xFF & !0x04;
        want[2] = 0xFF & !0x44;
        want[6] = 0xFF & !0x40;
        assert_eq!(acc, want);
    }

    #[test]
    fn pack_signs_decode_every_light() {
        // One light: the i8 itself.
        for b in [-1i8, 0, 1] {
            assert_eq!(pack_sign(b, 1, 0), b);
        }
        // Several: light k of the pack is +1 with bit k, -1 with bit 4 + k.
        let byte = (0b0010_1001u8) as i8; // light 0: +1, light 1: -1, light 2: 0, light 3: +1
        let want = [1i8, -1, 0, 1];
        for lights in [2usize, 4, 7] {
            for l in 0..lights {
                assert_eq!(pack_sign(byte, lights, l), want[l % PACK], "{lights} {l}");
            }
        }
    }

    #[test]
    fn sign_bytes_encode_lanes() {
        assert_eq!(
            sign_bytes(0b0000_0101, 0b1000_0010).map(|b| b as i8),
            [1, -1, 1, 0, 0, 0, 0, -1]
        );
    }
}
