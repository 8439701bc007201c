//! Meshes: primitives concatenated into one [`Mesh`], positions (float or quantized) and
//! indices decoded and checked, strips and fans turned into triangle lists.

use super::nodes::Loader;
use crate::SceneError;
use glam::Vec3;
use gltf::accessor::{DataType, Dimensions};
use gltf::mesh::Mode;
use shadowvol_mesh_topology::Mesh;

impl Loader<'_> {
    pub(super) fn read_mesh(
        &mut self,
        node_label: &str,
        mesh: &gltf::Mesh,
    ) -> Result<Mesh, SceneError> {
        let mut out = Mesh::default();
        let mesh_label = match mesh.name() {
            Some(n) => format!("{node_label}, mesh {} '{n}'", mesh.index()),
            None => format!("{node_label}, mesh {}", mesh.index()),
        };
        for prim in mesh.primitives() {
            let label = format!("{mesh_label}, primitive {}", prim.index());
            let mode = prim.mode();
            if !matches!(
                mode,
                Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
            ) {
                self.notes.push(format!(
                    "{}: {label}: mode {mode:?} is not a triangle mode, the primitive is skipped \
                     (shadow volumes need TRIANGLES, TRIANGLE_STRIP or TRIANGLE_FAN)",
                    self.source_name
                ));
                continue;
            }
            let draco = self.draco.get(&(mesh.index(), prim.index()));
            let Some(pos_acc) = prim.get(&gltf::Semantic::Positions) else {
                self.notes.push(format!(
                    "{}: {label}: no POSITION attribute, the primitive is skipped",
                    self.source_name
                ));
                continue;
            };
            let (positions, indices, idx_label) = match draco {
                // The Draco stream replaces the accessors' data (they have none, or a fallback).
                Some(ext) => {
                    let (p, i) = self.read_draco(&label, &prim, &pos_acc, ext)?;
                    (p, i, format!("{label}, KHR_draco_mesh_compression"))
                }
                None => {
                    let positions = self.read_positions(&label, &pos_acc)?;
                    let n = positions.len();
                    let indices: Vec<u32> = match prim.indices() {
                        Some(acc) => self.read_indices(&label, &acc, n)?,
                        None => (0..n as u32).collect(),
                    };
                    let idx_label = prim.indices().map_or_else(
                        || format!("{label} (non-indexed)"),
                        |a| format!("{label}, accessor {} (indices)", a.index()),
                    );
                    (positions, indices, idx_label)
                }
            };
            let n = positions.len();
            let tris = assemble(mode, &indices).map_err(|m| self.err(idx_label, m))?;
            let base = out.positions.len() as u64;
            if base + n as u64 >= u64::from(u32::MAX) {
                return Err(self.err(label, "too many vertices for u32 indexing"));
            }
            let base = base as u32;
            out.positions.extend_from_slice(&positions);
            out.triangles
                .extend(tris.iter().map(|t| [t[0] + base, t[1] + base, t[2] + base]));
        }
        out.validate()
            .map_err(|e| self.err(mesh_label, e.to_string()))?;
        Ok(out)
    }

    /// Positions as `f32`: `FLOAT`, or with `KHR_mesh_quantization` `BYTE`, `UNSIGNED_BYTE`,
    /// `SHORT`, `UNSIGNED_SHORT`, normalized or not (see the module documentation).
    fn read_positions(&self, label: &str, acc: &gltf::Accessor) -> Result<Vec<Vec3>, SceneError> {
        let alabel = format!("{label}, accessor {} (POSITION)", acc.index());
        let ty = acc.data_type();
        let allowed = ty == DataType::F32 || (self.quantization && ty != DataType::U32);
        if acc.dimensions() != Dimensions::Vec3 || !allowed {
            return Err(self.err(
                alabel,
                format!(
                    "POSITION must be VEC3 of FLOAT (or, with KHR_mesh_quantization in \
                     extensionsUsed, of BYTE, UNSIGNED_BYTE, SHORT or UNSIGNED_SHORT), found \
                     {:?} of {:?}",
                    acc.dimensions(),
                    ty
                ),
            ));
        }
        let normalized = acc.normalized();
        if normalized && ty == DataType::F32 {
            return Err(self.err(alabel, "a FLOAT accessor cannot be normalized"));
        }
        let bytes = self.accessor_bytes(&alabel, acc)?;
        let size = acc.size() / 3;
        let component = |c: &[u8]| -> f32 {
            match (ty, normalized) {
                (DataType::F32, _) => f32::from_le_bytes([c[0], c[1], c[2], c[3]]),
                (DataType::I8, false) => f32::from(c[0] as i8),
                (DataType::U8, false) => f32::from(c[0]),
                (DataType::I16, false) => f32::from(i16::from_le_bytes([c[0], c[1]])),
                (DataType::U16, false) => f32::from(u16::from_le_bytes([c[0], c[1]])),
                (DataType::I8, true) => (f32::from(c[0] as i8) / 127.0).max(-1.0),
                (DataType::U8, true) => f32::from(c[0]) / 255.0,
                (DataType::I16, true) => {
                    (f32::from(i16::from_le_bytes([c[0], c[1]])) / 32767.0).max(-1.0)
                }
                (DataType::U16, true) => f32::from(u16::from_le_bytes([c[0], c[1]])) / 65535.0,
                (DataType::U32, _) => f32::NAN,
            }
        };
        let mut out = Vec::with_capacity(acc.count());
        for (i, c) in bytes.chunks_exact(3 * size).enumerate() {
            let v = [
                component(&c[..size]),
                component(&c[size..2 * size]),
                component(&c[2 * size..]),
            ];
            for (axis, value) in ['x', 'y', 'z'].into_iter().zip(v) {
                if !value.is_finite() {
                    return Err(self.err(
                        alabel,
                        format!(
                            "element {i}: coordinate {axis} is {value}, but positions must be \
                             finite"
                        ),
                    ));
                }
            }
            out.push(Vec3::from_array(v));
        }
        Ok(out)
    }

    fn read_indices(
        &self,
        label: &str,
        acc: &gltf::Accessor,
        vertices: usize,
    ) -> Result<Vec<u32>, SceneError> {
        let alabel = format!("{label}, accessor {} (indices)", acc.index());
        if acc.dimensions() != Dimensions::Scalar
            || !matches!(
                acc.data_type(),
                DataType::U8 | DataType::U16 | DataType::U32
            )
        {
            return Err(self.err(
                alabel,
                format!(
                    "indices must be SCALAR of UNSIGNED_BYTE/SHORT/INT, found {:?} of {:?}",
                    acc.dimensions(),
                    acc.data_type()
                ),
            ));
        }
        let bytes = self.accessor_bytes(&alabel, acc)?;
        let values: Vec<u32> = match acc.data_type() {
            DataType::U8 => bytes.iter().map(|&b| u32::from(b)).collect(),
            DataType::U16 => bytes
                .chunks_exact(2)
                .map(|c| u32::from(u16::from_le_bytes([c[0], c[1]])))
                .collect(),
            _ => bytes
                .chunks_exact(4)
                .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]))
                .collect(),
        };
        if let Some((i, &v)) = values
            .iter()
            .enumerate()
            .find(|(_, &v)| v as usize >= vertices)
        {
            return Err(self.err(
                alabel,
                format!(
                    "element {i}: vertex index {v} is out of range (the primitive has {vertices} \
                     vertices)"
                ),
            ));
        }
        Ok(values)
    }
}

/// Turns an index list of a triangle mode into triangles.
fn assemble(mode: Mode, idx: &[u32]) -> Result<Vec<[u32; 3]>, String> {
    match mode {
        Mode::Triangles => {
            if !idx.len().is_multiple_of(3) {
                return Err(format!(
                    "{} indices do not make whole triangles (TRIANGLES needs a multiple of 3)",
                    idx.len()
                ));
            }
            Ok(idx.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect())
        }
        Mode::TriangleStrip | Mode::TriangleFan => {
            if idx.len() < 3 {
                return Err(format!(
                    "{} indices make no triangle ({mode:?} needs at least 3)",
                    idx.len()
                ));
            }
            Ok((0..idx.len() - 2)
                .map(|i| match mode {
                    Mode::TriangleFan => [idx[0], idx[i + 1], idx[i + 2]],
                    _ if i % 2 == 0 => [idx[i], idx[i + 1], idx[i + 2]],
                    _ => [idx[i + 1], idx[i], idx[i + 2]],
                })
                .collect())
        }
        _ => Err(format!("mode {mode:?} is not a triangle mode")),
    }
}
