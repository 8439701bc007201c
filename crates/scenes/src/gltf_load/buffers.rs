//! Buffer data: which buffers are loaded, `EXT_meshopt_compression` views decoded, data URIs,
//! and the bytes of an accessor (dense, zero-filled or sparse) checked against its view and
//! buffer.

use super::document::Extensions;
use super::nodes::Loader;
use super::Source;
use crate::SceneError;
use std::collections::HashMap;

impl Source<'_> {
    /// Checks that relative URIs percent-decode to UTF-8 (`import_buffers` panics otherwise).
    pub(super) fn check_buffer_uris(&self, document: &gltf::Document) -> Result<(), SceneError> {
        for b in document.buffers() {
            if let gltf::buffer::Source::Uri(uri) = b.source() {
                if !uri.contains(':') && std::str::from_utf8(&percent_decode(uri)).is_err() {
                    return Err(self.err(
                        "buffers",
                        format!(
                            "buffer {}: uri {uri:?} percent-decodes to bytes that are not UTF-8",
                            b.index()
                        ),
                    ));
                }
            }
        }
        Ok(())
    }

    /// Each buffer's data, or `None` for one that positions and indices do not read.
    pub(super) fn load_buffers(
        &self,
        document: &gltf::Document,
        ext: &Extensions,
        mut blob: Option<Vec<u8>>,
    ) -> Result<Vec<Option<Vec<u8>>>, SceneError> {
        // Only the buffers that positions and indices read are loaded (others may be
        // placeholders without data, or URIs this loader cannot resolve, which is valid glTF).
        // An EXT_meshopt_compression fallback buffer has no data; its views are decoded instead.
        let needed = needed_buffers(document, ext);
        let mut data: Vec<Option<Vec<u8>>> = Vec::with_capacity(document.buffers().len());
        for b in document.buffers() {
            let bin = matches!(b.source(), gltf::buffer::Source::Bin);
            if !needed.contains(&b.index()) || (ext.fallback.contains(&b.index()) && bin) {
                if bin && b.index() == 0 {
                    // The GLB's BIN chunk belongs to buffer 0 only.
                    blob = None;
                }
                data.push(None);
                continue;
            }
            data.push(Some(self.load_buffer(&b, &mut blob)?));
        }
        Ok(data)
    }

    /// One needed buffer's data, from its URI or the GLB's BIN chunk, cut to `byteLength`.
    fn load_buffer(
        &self,
        b: &gltf::Buffer,
        blob: &mut Option<Vec<u8>>,
    ) -> Result<Vec<u8>, SceneError> {
        if matches!(b.source(), gltf::buffer::Source::Bin) && blob.is_none() {
            // Valid glTF JSON (a buffer without `uri` names the GLB's binary chunk), but a
            // `.gltf` has no such chunk, so the positions or indices it should hold are missing.
            return Err(self.err(
                "buffers",
                format!(
                    "buffer {} has no uri and no GLB binary chunk holds it (a .gltf has none; in \
                     a .glb only buffer 0 uses it): the {} bytes its positions or indices are read \
                     from are not in the file",
                    b.index(),
                    b.length()
                ),
            ));
        }
        let d = gltf::buffer::Data::from_source_and_blob(b.source(), self.base, blob)
            .map_err(|e| self.err("buffers", format!("buffer {}: {e}", b.index())))?;
        // Data shorter than byteLength is refused; data longer than it (beyond the up to 3
        // padding bytes a GLB BIN chunk may carry) is a lie about the length too. Views are then
        // checked against the declared length only.
        if d.0.len() < b.length() || d.0.len() > b.length() + 3 {
            return Err(self.err(
                "buffers",
                format!(
                    "buffer {}: its data holds {} bytes but byteLength declares {} (a data URI, \
                     file or GLB chunk must match byteLength)",
                    b.index(),
                    d.0.len(),
                    b.length()
                ),
            ));
        }
        let mut d = d.0;
        d.truncate(b.length());
        Ok(d)
    }
}

/// The buffers that positions and indices read: the buffers of their views (and sparse views),
/// or, for `EXT_meshopt_compression` views, the buffer of the compressed source; for a
/// `KHR_draco_mesh_compression` primitive, only the buffer of its Draco stream's view.
fn needed_buffers(document: &gltf::Document, ext: &Extensions) -> std::collections::HashSet<usize> {
    let mut out = std::collections::HashSet::new();
    let mut add = |v: gltf::buffer::View| {
        match ext
            .meshopt
            .get(&v.index())
            .and_then(|e| e.get("buffer"))
            .and_then(|b| b.as_u64())
        {
            Some(src) => out.insert(src as usize),
            None => out.insert(v.buffer().index()),
        };
    };
    let views: Vec<gltf::buffer::View> = document.views().collect();
    for mesh in document.meshes() {
        for prim in mesh.primitives() {
            if let Some(e) = ext.draco.get(&(mesh.index(), prim.index())) {
                let view = e.get("bufferView").and_then(serde_json::Value::as_u64);
                if let Some(v) = view.and_then(|v| views.get(usize::try_from(v).ok()?)) {
                    add(v.clone());
                }
                continue;
            }
            for acc in [prim.get(&gltf::Semantic::Positions), prim.indices()]
                .into_iter()
                .flatten()
            {
                if let Some(v) = acc.view() {
                    add(v);
                }
                if let Some(s) = acc.sparse() {
                    add(s.indices().view());
                    add(s.values().view());
                }
            }
        }
    }
    out
}

/// Decodes the `EXT_meshopt_compression` views that positions and indices read (views of
/// other attributes are left alone). Errors are `(context, message)`.
pub(super) fn decode_meshopt_views(
    document: &gltf::Document,
    ext: &Extensions,
    buffers: &[Option<&[u8]>],
) -> Result<HashMap<usize, Vec<u8>>, (String, String)> {
    let mut wanted = std::collections::HashSet::new();
    let mut want = |acc: gltf::Accessor| {
        if let Some(v) = acc.view() {
            wanted.insert(v.index());
        }
        if let Some(s) = acc.sparse() {
            wanted.insert(s.indices().view().index());
            wanted.insert(s.values().view().index());
        }
    };
    for mesh in document.meshes() {
        for prim in mesh.primitives() {
            if ext.draco.contains_key(&(mesh.index(), prim.index())) {
                continue;
            }
            if let Some(a) = prim.get(&gltf::Semantic::Positions) {
                want(a);
            }
            if let Some(a) = prim.indices() {
                want(a);
            }
        }
    }
    let mut out = HashMap::new();
    for view in document.views().filter(|v| wanted.contains(&v.index())) {
        let Some(e) = ext.meshopt.get(&view.index()) else {
            continue;
        };
        let ctx = format!("buffer view {}, EXT_meshopt_compression", view.index());
        let bad = |m: String| (ctx.clone(), m);
        let uint = |k: &str| -> Result<Option<usize>, (String, String)> {
            match e.get(k) {
                None => Ok(None),
                Some(v) => v
                    .as_u64()
                    .and_then(|x| usize::try_from(x).ok())
                    .map(Some)
                    .ok_or_else(|| {
                        bad(format!("\"{k}\" must be a non-negative integer, found {v}"))
                    }),
            }
        };
        let need = |k: &str| uint(k)?.ok_or_else(|| bad(format!("\"{k}\" is missing")));
        let name = |k: &str, default: Option<&str>| -> Result<String, (String, String)> {
            match e.get(k) {
                None => default
                    .map(str::to_owned)
                    .ok_or_else(|| bad(format!("\"{k}\" is missing"))),
                Some(serde_json::Value::String(s)) => Ok(s.clone()),
                Some(v) => Err(bad(format!("\"{k}\" must be a string, found {v}"))),
            }
        };
        let src_index = need("buffer")?;
        let offset = uint("byteOffset")?.unwrap_or(0);
        let length = need("byteLength")?;
        let stride = need("byteStride")?;
        let count = need("count")?;
        let mode_name = name("mode", None)?;
        let filter_name = name("filter", Some("NONE"))?;
        let mode = crate::meshopt_view::Mode::from_name(&mode_name)
            .ok_or_else(|| bad(format!("unknown mode {mode_name:?}")))?;
        let filter = crate::meshopt_view::Filter::from_name(&filter_name)
            .ok_or_else(|| bad(format!("unknown filter {filter_name:?}")))?;
        let src = match buffers.get(src_index) {
            Some(Some(b)) => *b,
            Some(None) => {
                return Err(bad(format!(
                    "source buffer {src_index} is a fallback buffer without data"
                )))
            }
            None => return Err(bad(format!("source buffer {src_index} does not exist"))),
        };
        let encoded = offset
            .checked_add(length)
            .filter(|&end| end <= src.len())
            .map(|end| &src[offset..end])
            .ok_or_else(|| {
                bad(format!(
                    "source range byteOffset {offset}, byteLength {length} runs past the end of \
                     buffer {src_index} ({} bytes)",
                    src.len()
                ))
            })?;
        if count.checked_mul(stride) != Some(view.length()) {
            return Err(bad(format!(
                "count {count} x byteStride {stride} does not equal the view's byteLength {}",
                view.length()
            )));
        }
        let bytes =
            crate::meshopt_view::decode(encoded, count, stride, mode, filter).map_err(bad)?;
        out.insert(view.index(), bytes);
    }
    Ok(out)
}

/// The bytes available and where that number comes from, when an allocation of `needed` bytes
/// that the file does not bound (zeros of a declared count, a decoder's declared tables) is
/// larger than [`shadowvol_mesh_topology::MEMORY_CHECK_THRESHOLD`] and than what is available
/// ([`shadowvol_mesh_topology::available_memory`]); `None` when it may go ahead.
pub(super) fn memory_shortfall(needed: u64) -> Option<(u64, String)> {
    if needed <= shadowvol_mesh_topology::MEMORY_CHECK_THRESHOLD {
        return None;
    }
    shadowvol_mesh_topology::available_memory().filter(|(available, _)| needed > *available)
}

/// `%XX` escapes decoded to bytes (anything else kept as is), as the gltf crate decodes relative
/// URIs.
fn percent_decode(uri: &str) -> Vec<u8> {
    let b = uri.as_bytes();
    let hex = |c: u8| (c as char).to_digit(16);
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        if b[i] == b'%' && i + 2 < b.len() {
            if let (Some(h), Some(l)) = (hex(b[i + 1]), hex(b[i + 2])) {
                out.push((h * 16 + l) as u8);
                i += 3;
                continue;
            }
        }
        out.push(b[i]);
        i += 1;
    }
    out
}

impl Loader<'_> {
    /// The accessor's elements, tightly packed (`count * size` bytes), with bounds checks and
    /// sparse substitution.
    pub(super) fn accessor_bytes(
        &self,
        alabel: &str,
        acc: &gltf::Accessor,
    ) -> Result<Vec<u8>, SceneError> {
        let count = acc.count();
        let size = acc.size();
        if count == 0 {
            return Err(self.err(alabel.to_owned(), "count is 0 (at least 1 element needed)"));
        }
        let total = count
            .checked_mul(size)
            .ok_or_else(|| self.err(alabel.to_owned(), format!("count {count} overflows")))?;
        let mut out = match acc.view() {
            None => self.zero_elements(alabel, count, total)?,
            Some(view) => self.view_elements(alabel, acc, &view)?,
        };
        if let Some(sparse) = acc.sparse() {
            self.substitute_sparse(alabel, acc, &sparse, &mut out)?;
        }
        Ok(out)
    }

    /// A view-less accessor's zeros, after a memory check: the file does not bound them.
    fn zero_elements(
        &self,
        alabel: &str,
        count: usize,
        total: usize,
    ) -> Result<Vec<u8>, SceneError> {
        if let Some((available, source)) = memory_shortfall(total as u64) {
            return Err(self.err(
                alabel.to_owned(),
                format!(
                    "{count} elements without a bufferView need {total} bytes, more than the \
                     {available} bytes available ({source})"
                ),
            ));
        }
        let mut v = Vec::new();
        v.try_reserve_exact(total).map_err(|_| {
            self.err(
                alabel.to_owned(),
                format!("{count} elements without a bufferView: cannot allocate {total} bytes"),
            )
        })?;
        v.resize(total, 0u8);
        Ok(v)
    }

    /// The accessor's elements packed from its buffer view, after stride and bounds checks.
    fn view_elements(
        &self,
        alabel: &str,
        acc: &gltf::Accessor,
        view: &gltf::buffer::View,
    ) -> Result<Vec<u8>, SceneError> {
        let (count, size) = (acc.count(), acc.size());
        let stride = view.stride().unwrap_or(size);
        if stride < size {
            return Err(self.err(
                alabel.to_owned(),
                format!(
                    "buffer view {} has byteStride {stride}, smaller than the element size {size}",
                    view.index()
                ),
            ));
        }
        let data = self.view_bytes(alabel, view)?;
        let needed = acc
            .offset()
            .checked_add((count - 1).saturating_mul(stride))
            .and_then(|x| x.checked_add(size));
        match needed {
            Some(needed) if needed <= data.len() => {}
            _ => {
                return Err(self.err(
                    alabel.to_owned(),
                    format!(
                        "{count} elements of {size} bytes (stride {stride}, byteOffset {}) run \
                         past the end of buffer view {} ({} bytes)",
                        acc.offset(),
                        view.index(),
                        data.len()
                    ),
                ))
            }
        }
        let mut v = Vec::with_capacity(count * size);
        for i in 0..count {
            let s = acc.offset() + i * stride;
            v.extend_from_slice(&data[s..s + size]);
        }
        Ok(v)
    }

    /// Replaces the elements that the sparse indices name by the sparse values.
    fn substitute_sparse(
        &self,
        alabel: &str,
        acc: &gltf::Accessor,
        sparse: &gltf::accessor::sparse::Sparse,
        out: &mut [u8],
    ) -> Result<(), SceneError> {
        let (count, size) = (acc.count(), acc.size());
        let n = sparse.count();
        let idx = sparse.indices();
        let isize = match idx.index_type() {
            gltf::accessor::sparse::IndexType::U8 => 1,
            gltf::accessor::sparse::IndexType::U16 => 2,
            gltf::accessor::sparse::IndexType::U32 => 4,
        };
        let slabel = format!("{alabel}, sparse");
        let idata = self.view_bytes(&slabel, &idx.view())?;
        let vdata = self.view_bytes(&slabel, &sparse.values().view())?;
        let ioff = idx.offset();
        let voff = sparse.values().offset();
        let ifits = n
            .checked_mul(isize)
            .and_then(|x| x.checked_add(ioff))
            .is_some_and(|e| e <= idata.len());
        let vfits = n
            .checked_mul(size)
            .and_then(|x| x.checked_add(voff))
            .is_some_and(|e| e <= vdata.len());
        if !ifits || !vfits {
            return Err(self.err(
                slabel,
                format!("{n} sparse indices or values run past the end of their buffer views"),
            ));
        }
        for k in 0..n {
            let c = &idata[ioff + k * isize..ioff + (k + 1) * isize];
            let target = match isize {
                1 => usize::from(c[0]),
                2 => usize::from(u16::from_le_bytes([c[0], c[1]])),
                _ => u32::from_le_bytes([c[0], c[1], c[2], c[3]]) as usize,
            };
            if target >= count {
                return Err(self.err(
                    slabel,
                    format!(
                        "sparse index {k} targets element {target}, but the accessor has {count}"
                    ),
                ));
            }
            out[target * size..(target + 1) * size]
                .copy_from_slice(&vdata[voff + k * size..voff + (k + 1) * size]);
        }
        Ok(())
    }

    /// The bytes of buffer `view`: decoded when it is `EXT_meshopt_compression`-compressed, else
    /// its range of its buffer, checked to lie inside the buffer.
    pub(super) fn view_bytes(
        &self,
        alabel: &str,
        view: &gltf::buffer::View,
    ) -> Result<&[u8], SceneError> {
        if let Some(d) = self.decoded.get(&view.index()) {
            return Ok(d);
        }
        let buf = match self.buffers.get(view.buffer().index()) {
            Some(Some(b)) => *b,
            Some(None) => {
                return Err(self.err(
                    alabel.to_owned(),
                    format!(
                        "buffer view {} is in buffer {}, an EXT_meshopt_compression fallback \
                         without data, but the view is not compressed",
                        view.index(),
                        view.buffer().index()
                    ),
                ))
            }
            None => {
                return Err(self.err(
                    alabel.to_owned(),
                    format!("buffer {} is missing", view.buffer().index()),
                ))
            }
        };
        let end = view.offset().checked_add(view.length());
        match end {
            Some(end) if end <= buf.len() => Ok(&buf[view.offset()..end]),
            _ => Err(self.err(
                alabel.to_owned(),
                format!(
                    "buffer view {} (byteOffset {}, byteLength {}) runs past the end of buffer {} \
                     ({} bytes)",
                    view.index(),
                    view.offset(),
                    view.length(),
                    view.buffer().index(),
                    buf.len()
                ),
            )),
        }
    }
}
