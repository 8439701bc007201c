//! Decoding of `EXT_meshopt_compression` buffer views, with the `meshopt` crate (bindings to
//! meshoptimizer, whose decoders are the reference implementation of the extension and are
//! safe on untrusted input).
//!
//! A compressed buffer view names a source range in another buffer and how to decode it: `count`
//! elements of `byteStride` bytes, in one of three modes (`ATTRIBUTES`: a vertex stream;
//! `TRIANGLES`: an index buffer of whole triangles; `INDICES`: any index sequence), optionally
//! followed by a filter (`OCTAHEDRAL`, `QUATERNION`, `EXPONENTIAL`, `COLOR`). The result is the
//! view's data, `count * byteStride` bytes. The extension's limits are checked here before the
//! decoder sees the data (meshoptimizer asserts them): `ATTRIBUTES` strides are multiples of 4 up
//! to 256, index strides are 2 or 4, `TRIANGLES` counts are multiples of 3, and each filter
//! needs the strides it is defined for.
//!
//! ```
//! use shadowvol_scenes::meshopt_view::{decode, Filter, Mode};
//!
//! let indices = [0u32, 1, 2, 2, 1, 3];
//! let encoded = meshopt::encode_index_buffer(&indices, 4).unwrap();
//! let bytes = decode(&encoded, 6, 4, Mode::Triangles, Filter::None).unwrap();
//! assert_eq!(bytes, indices.iter().flat_map(|i| i.to_le_bytes()).collect::<Vec<u8>>());
//! assert!(decode(&encoded, 5, 4, Mode::Triangles, Filter::None).is_err()); // not whole triangles
//! ```

/// How a compressed view is encoded (`mode` of the extension object).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mode {
    /// A vertex stream (`meshopt_decodeVertexBuffer`).
    Attributes,
    /// An index buffer of whole triangles (`meshopt_decodeIndexBuffer`).
    Triangles,
    /// An index sequence (`meshopt_decodeIndexSequence`).
    Indices,
}

/// The filter applied after decoding (`filter` of the extension object; `ATTRIBUTES` only).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Filter {
    /// No filter.
    None,
    /// Octahedral unit vectors (8 or 16 bits per component).
    Octahedral,
    /// Quaternions (16 bits per component).
    Quaternion,
    /// Floats as shared-exponent integers (32 bits per component).
    Exponential,
    /// YCoCg colours (8 or 16 bits per component).
    Color,
}

impl Mode {
    /// The mode named `s` in the extension (`"ATTRIBUTES"`, `"TRIANGLES"`, `"INDICES"`).
    #[must_use]
    pub fn from_name(s: &str) -> Option<Self> {
        match s {
            "ATTRIBUTES" => Some(Self::Attributes),
            "TRIANGLES" => Some(Self::Triangles),
            "INDICES" => Some(Self::Indices),
            _ => None,
        }
    }
}

impl Filter {
    /// The filter named `s` in the extension (`"NONE"`, `"OCTAHEDRAL"`, `"QUATERNION"`,
    /// `"EXPONENTIAL"`, `"COLOR"`).
    #[must_use]
    pub fn from_name(s: &str) -> Option<Self> {
        match s {
            "NONE" => Some(Self::None),
            "OCTAHEDRAL" => Some(Self::Octahedral),
            "QUATERNION" => Some(Self::Quaternion),
            "EXPONENTIAL" => Some(Self::Exponential),
            "COLOR" => Some(Self::Color),
            _ => None,
        }
    }
}

/// The largest ratio of decoded to encoded bytes accepted. meshoptimizer's vertex codec spends at
/// least 2 bits per 16 bytes of a byte column (ratio 64) and its index codecs at least a byte per
/// triangle or index; a larger declared size is a lie that would only allocate memory.
const MAX_RATIO: usize = 1024;

/// Element of a vertex stream of `N` bytes (the decoder's vertex size is `size_of`).
#[derive(Clone, Copy)]
struct Block<const N: usize>([u8; N]);

impl<const N: usize> Default for Block<N> {
    fn default() -> Self {
        Self([0; N])
    }
}

fn vertices<const N: usize>(encoded: &[u8], count: usize) -> Result<Vec<u8>, String> {
    let v = meshopt::decode_vertex_buffer::<Block<N>>(encoded, count)
        .map_err(|e| format!("the vertex stream does not decode ({e})"))?;
    Ok(v.iter().flat_map(|b| b.0).collect())
}

macro_rules! by_stride {
    ($stride:expr, $encoded:expr, $count:expr, $($n:literal)*) => {
        match $stride {
            $($n => vertices::<$n>($encoded, $count),)*
            s => Err(format!("byteStride {s} is not a multiple of 4 from 4 to 256 (ATTRIBUTES)")),
        }
    };
}

/// Decodes `count` elements of `stride` bytes from `encoded`; returns `count * stride` bytes.
///
/// # Errors
/// A message saying what is wrong: a stride or count the mode or filter does not allow, a
/// declared size more than 1024 times the encoded size, or data the decoder rejects.
pub fn decode(
    encoded: &[u8],
    count: usize,
    stride: usize,
    mode: Mode,
    filter: Filter,
) -> Result<Vec<u8>, String> {
    let total = count
        .checked_mul(stride)
        .ok_or_else(|| format!("count {count} x byteStride {stride} overflows"))?;
    if total > encoded.len().saturating_mul(MAX_RATIO).saturating_add(4096) {
        return Err(format!(
            "count {count} x byteStride {stride} = {total} bytes from {} encoded bytes: more \
             than the codec can produce",
            encoded.len()
        ));
    }
    if mode != Mode::Attributes && filter != Filter::None {
        return Err(format!(
            "filter {filter:?} is only allowed with mode ATTRIBUTES"
        ));
    }
    let mut data = match mode {
        Mode::Attributes => by_stride!(stride, encoded, count,
            4 8 12 16 20 24 28 32 36 40 44 48 52 56 60 64 68 72 76 80 84 88 92 96 100 104 108 112
            116 120 124 128 132 136 140 144 148 152 156 160 164 168 172 176 180 184 188 192 196
            200 204 208 212 216 220 224 228 232 236 240 244 248 252 256)?,
        Mode::Triangles | Mode::Indices => {
            if mode == Mode::Triangles && !count.is_multiple_of(3) {
                return Err(format!(
                    "count {count} is not a multiple of 3 (TRIANGLES decodes whole triangles)"
                ));
            }
            let what = if mode == Mode::Triangles {
                "index buffer"
            } else {
                "index sequence"
            };
            let bad = |e: meshopt::Error| format!("the {what} does not decode ({e})");
            match (stride, mode) {
                (2, Mode::Triangles) => to_bytes(
                    &meshopt::decode_index_buffer::<u16>(encoded, count).map_err(bad)?,
                    u16::to_le_bytes,
                ),
                (4, Mode::Triangles) => to_bytes(
                    &meshopt::decode_index_buffer::<u32>(encoded, count).map_err(bad)?,
                    u32::to_le_bytes,
                ),
                (2, _) => to_bytes(
                    &meshopt::decode_index_sequence::<u16>(encoded, count).map_err(bad)?,
                    u16::to_le_bytes,
                ),
                (4, _) => to_bytes(
                    &meshopt::decode_index_sequence::<u32>(encoded, count).map_err(bad)?,
                    u32::to_le_bytes,
                ),
                (s, _) => return Err(format!("byteStride {s} of an index view must be 2 or 4")),
            }
        }
    };
    apply_filter(&mut data, stride, filter)?;
    Ok(data)
}

fn to_bytes<T: Copy, const N: usize>(v: &[T], f: fn(T) -> [u8; N]) -> Vec<u8> {
    v.iter().flat_map(|&x| f(x)).collect()
}

fn apply_filter(data: &mut [u8], stride: usize, filter: Filter) -> Result<(), String> {
    let need = |ok: bool, what: &str| {
        if ok {
            Ok(())
        } else {
            Err(format!(
                "filter {filter:?} needs byteStride {what}, found {stride}"
            ))
        }
    };
    match filter {
        Filter::None => Ok(()),
        Filter::Octahedral | Filter::Color => {
            need(stride == 4 || stride == 8, "4 or 8")?;
            if stride == 4 {
                let mut v: Vec<[i8; 4]> = data
                    .chunks_exact(4)
                    .map(|c| [c[0] as i8, c[1] as i8, c[2] as i8, c[3] as i8])
                    .collect();
                if filter == Filter::Octahedral {
                    meshopt::decode_filter_oct(&mut v);
                } else {
                    meshopt::decode_filter_color(&mut v);
                }
                for (c, x) in data.chunks_exact_mut(4).zip(&v) {
                    c.copy_from_slice(&x.map(|b| b as u8));
                }
            } else {
                let mut v = words16(data);
                if filter == Filter::Octahedral {
                    meshopt::decode_filter_oct(&mut v);
                } else {
                    meshopt::decode_filter_color(&mut v);
                }
                put16(data, &v);
            }
            Ok(())
        }
        Filter::Quaternion => {
            need(stride == 8, "8")?;
            let mut v = words16(data);
            meshopt::decode_filter_quat(&mut v);
            put16(data, &v);
            Ok(())
        }
        Filter::Exponential => {
            need(stride.is_multiple_of(4), "a multiple of 4")?;
            // Each 32-bit component is decoded on its own, so the stream is one component per
            // element.
            let mut v: Vec<[u32; 1]> = data
                .chunks_exact(4)
                .map(|c| [u32::from_le_bytes([c[0], c[1], c[2], c[3]])])
                .collect();
            meshopt::decode_filter_exp(&mut v);
            for (c, x) in data.chunks_exact_mut(4).zip(&v) {
                c.copy_from_slice(&x[0].to_le_bytes());
            }
            Ok(())
        }
    }
}

fn words16(data: &[u8]) -> Vec<[i16; 4]> {
    data.chunks_exact(8)
        .map(|c| {
            let w = |k: usize| i16::from_le_bytes([c[2 * k], c[2 * k + 1]]);
            [w(0), w(1), w(2), w(3)]
        })
        .collect()
}

fn put16(data: &mut [u8], v: &[[i16; 4]]) {
    for (c, x) in data.chunks_exact_mut(8).zip(v) {
        for k in 0..4 {
            c[2 * k..2 * k + 2].copy_from_slice(&x[k].to_le_bytes());
        }
    }
}
