//! The ray-traced reference and the artifact metric.
//!
//! For every covered pixel, the rasterized ids name the triangle the pre-pass kept. The surface
//! point is the intersection of the pixel-centre ray (from the same camera, in `f64`) with that
//! triangle's plane; that `f64` point is the reference's input. From it, a shadow segment goes to
//! each light (to a point light; towards a directional one, a ray) through a BVH over all world
//! caster triangles (the same `f32` positions the GPU drew), skipping the triangle itself. Every
//! caster whose box the segment reaches is decided exactly ([`crate::occlusion`]): it blocks when
//! the surface point and the light lie strictly on opposite sides of its plane and the line
//! through them meets the closed triangle. A light in a caster's plane (edge-on) or on the caster
//! does not block it, as the volumes' sign 0 casts nothing. Run in parallel with rayon.
//!
//! Per pixel and light the state is background, unlit (the surface faces away from the light,
//! the light adds less than one 8-bit step there ([`faces_light`]), or the light is blocked) or
//! lit. [`Comparison::geometric_artifact_pixels`] repeats the count with the geometric facing
//! ([`faces_light_geometric`], any `cos θ > 0`), where rasterized volumes z-fight with faces the
//! light grazes even for exact silhouettes (see the crate README). The raster state uses the same
//! surface point and facing and the stencil (0 = lit). A pixel is an *artifact* when, for some
//! light, the raster state differs from the reference and the reference state is the same over
//! the pixel's 3×3 neighbourhood (that is, the pixel is more than one pixel away from a reference
//! shadow boundary); [`Comparison::boundary_pixels`] counts the differences within one pixel of
//! a boundary and [`Comparison::undecidable_pixels`] the pixels the reference could not decide.
//!
//! Why our own BVH: the `bvh` crate (0.13) needs Rust 1.90 (the workspace's MSRV is 1.89) and
//! brings in nalgebra; a median-split BVH over `glam` types is a hundred lines and keeps the
//! traversal (padded boxes, so that rounding never drops a candidate) in our hands.

use crate::occlusion::{light_side, Caster, Crossing, ShadowRay};
use crate::Frame;
use glam::{DMat4, DVec3, DVec4};
use rayon::prelude::*;

/// Per-pixel state for one light.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[repr(u8)]
pub enum PixelState {
    /// No surface.
    Background = 0,
    /// Surface facing away from the light or blocked.
    Unlit = 1,
    /// Surface lit.
    Lit = 2,
    /// Reference only: the answer hangs on the surface point's last `f64` bits: no caster
    /// blocks, but one touches the surface point while the shadow ray grazes its plane into it
    /// ([`crate::occlusion::Crossing::Undecidable`]). Never counted as an artifact.
    Uncertain = 3,
}

/// A bounding volume hierarchy over triangles (median split on the longest centroid axis,
/// leaves of at most 4 triangles).
#[derive(Debug, Clone, Default)]
pub struct Bvh {
    nodes: Vec<Node>,
    order: Vec<u32>,
    tris: Vec<[DVec3; 3]>,
    ids: Vec<u32>,
}

#[derive(Debug, Clone, Copy)]
struct Node {
    lo: DVec3,
    hi: DVec3,
    /// Leaf: first index into `order`; inner: index of the left child (right = left + 1).
    first: u32,
    /// Leaf: number of triangles (> 0); inner: 0.
    count: u32,
}

const LEAF: usize = 4;
/// Relative padding of the BVH boxes (`2⁻⁴⁰`).
const BOX_PAD: f64 = 1.0 / 1_099_511_627_776.0;

impl Bvh {
    /// Builds the hierarchy; triangle ids are the indices into `tris`.
    #[must_use]
    pub fn build(tris: Vec<[DVec3; 3]>) -> Self {
        let ids = (0..tris.len() as u32).collect();
        Self::build_with_ids(tris, ids)
    }

    /// Builds the hierarchy with a caller's id per triangle (what `skip` refers to).
    ///
    /// # Panics
    /// Panics if `ids.len() != tris.len()`.
    #[must_use]
    pub fn build_with_ids(tris: Vec<[DVec3; 3]>, ids: Vec<u32>) -> Self {
        assert_eq!(tris.len(), ids.len(), "one id per triangle");
        let mut order: Vec<u32> = (0..tris.len() as u32).collect();
        let centroids: Vec<DVec3> = tris.iter().map(|t| (t[0] + t[1] + t[2]) / 3.0).collect();
        let mut nodes = Vec::with_capacity(2 * tris.len() / LEAF + 1);
        nodes.push(Node {
            lo: DVec3::ZERO,
            hi: DVec3::ZERO,
            first: 0,
            count: 0,
        });
        let mut stack = vec![(0usize, 0usize, tris.len())];
        while let Some((node, begin, end)) = stack.pop() {
            let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
            let (mut clo, mut chi) = (lo, hi);
            for &i in &order[begin..end] {
                for p in tris[i as usize] {
                    lo = lo.min(p);
                    hi = hi.max(p);
                }
                clo = clo.min(centroids[i as usize]);
                chi = chi.max(centroids[i as usize]);
            }
            // Padded by 2⁻⁴⁰ of the box's magnitude, so that the rounding of the slab test can
            // never drop a triangle a shadow ray meets exactly (at a corner or along a face).
            let pad = lo.abs().max(hi.abs()) * BOX_PAD + DVec3::splat(f64::MIN_POSITIVE);
            nodes[node].lo = lo - pad;
            nodes[node].hi = hi + pad;
            let ext = chi - clo;
            if end - begin <= LEAF || ext.max_element() <= 0.0 {
                nodes[node].first = begin as u32;
                nodes[node].count = (end - begin) as u32;
                continue;
            }
            let axis = if ext.x >= ext.y && ext.x >= ext.z {
                0
            } else if ext.y >= ext.z {
                1
            } else {
                2
            };
            let mid = begin + (end - begin) / 2;
            order[begin..end].select_nth_unstable_by(mid - begin, |&a, &b| {
                centroids[a as usize][axis].total_cmp(&centroids[b as usize][axis])
            });
            let left = nodes.len();
            nodes.push(nodes[node]);
            nodes.push(nodes[node]);
            nodes[node].first = left as u32;
            nodes[node].count = 0;
            stack.push((left, begin, mid));
            stack.push((left + 1, mid, end));
        }
        Self {
            nodes,
            order,
            tris,
            ids,
        }
    }

    /// True when the segment `origin + t·dir`, `t ∈ (t_min, t_max)`, hits a triangle other than
    /// `skip`.
    #[must_use]
    pub fn occluded(&self, origin: DVec3, dir: DVec3, t_min: f64, t_max: f64, skip: u32) -> bool {
        self.occluded_by(origin, dir, t_min, t_max, |id| id != skip)
    }

    /// True when the segment `origin + t·dir`, `t ∈ (t_min, t_max)`, hits a triangle whose id
    /// passes `accept`.
    #[must_use]
    pub fn occluded_by(
        &self,
        origin: DVec3,
        dir: DVec3,
        t_min: f64,
        t_max: f64,
        accept: impl Fn(u32) -> bool,
    ) -> bool {
        self.traverse(origin, dir, t_min, t_max, |i| {
            accept(self.ids[i])
                && intersect(&self.tris[i], origin, dir).is_some_and(|t| t > t_min && t < t_max)
        })
    }
}

impl Bvh {
    /// Calls `visit(index)` for every triangle whose (padded) box the segment
    /// `origin + t·dir`, `t ∈ [0, t_max]`, meets, until it returns true; `index` is the position
    /// of the triangle in the list given to [`Bvh::build_with_ids`]. Returns whether some call
    /// returned true.
    pub fn visit(
        &self,
        origin: DVec3,
        dir: DVec3,
        t_max: f64,
        visit: impl FnMut(usize) -> bool,
    ) -> bool {
        self.traverse(origin, dir, 0.0, t_max, visit)
    }

    /// Calls `visit(index)` for the triangles whose (padded) box meets the segment
    /// `t ∈ [t_min, t_max]`, until it returns true; returns whether some call did.
    fn traverse(
        &self,
        origin: DVec3,
        dir: DVec3,
        t_min: f64,
        t_max: f64,
        mut visit: impl FnMut(usize) -> bool,
    ) -> bool {
        if self.tris.is_empty() {
            return false;
        }
        let inv = DVec3::ONE / dir;
        let mut stack = [0u32; 64];
        let mut sp = 1;
        while sp > 0 {
            sp -= 1;
            let n = self.nodes[stack[sp] as usize];
            if !slab(n.lo, n.hi, origin, inv, t_min, t_max) {
                continue;
            }
            if n.count > 0 {
                for &i in &self.order[n.first as usize..(n.first + n.count) as usize] {
                    if visit(i as usize) {
                        return true;
                    }
                }
            } else if sp + 2 <= stack.len() {
                stack[sp] = n.first;
                stack[sp + 1] = n.first + 1;
                sp += 2;
            }
        }
        false
    }
}

fn slab(lo: DVec3, hi: DVec3, o: DVec3, inv: DVec3, t_min: f64, t_max: f64) -> bool {
    let t1 = (lo - o) * inv;
    let t2 = (hi - o) * inv;
    // NaN (0 * inf) on an axis the ray is parallel to and touching: treat as overlapping.
    let tn = t1.min(t2);
    let tf = t1.max(t2);
    let mut near = t_min;
    let mut far = t_max;
    for k in 0..3 {
        if !tn[k].is_nan() {
            near = near.max(tn[k]);
        }
        if !tf[k].is_nan() {
            far = far.min(tf[k]);
        }
    }
    near <= far * (1.0 + 1e-12) + 1e-300
}

/// Möller–Trumbore in `f64`; `None` for a miss or a ray in the triangle's plane.
fn intersect(t: &[DVec3; 3], o: DVec3, d: DVec3) -> Option<f64> {
    let e1 = t[1] - t[0];
    let e2 = t[2] - t[0];
    let p = d.cross(e2);
    let det = e1.dot(p);
    if det == 0.0 || !det.is_finite() {
        return None;
    }
    let inv = 1.0 / det;
    let s = o - t[0];
    let u = s.dot(p) * inv;
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let q = s.cross(e1);
    let v = d.dot(q) * inv;
    if v < 0.0 || u + v > 1.0 {
        return None;
    }
    Some(e2.dot(q) * inv)
}

/// The surface point of one pixel.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SurfacePoint {
    /// World position (`f64`) on the rasterized triangle's plane, under the pixel centre.
    pub position: DVec3,
    /// Geometric normal turned towards the camera (unnormalised).
    pub normal: DVec3,
    /// Global triangle index (objects concatenated).
    pub triangle: u32,
    /// Largest albedo channel of the pixel's object (how much a light can change the pixel).
    pub albedo: f32,
}

/// The surface points of every pixel (`None` for background).
#[must_use]
pub fn surface_points(frame: &Frame) -> Vec<Option<SurfacePoint>> {
    let (w, h) = (frame.width as usize, frame.height as usize);
    let aspect = f64::from(frame.width) / f64::from(frame.height);
    let inv: DMat4 = frame.camera.view_proj_f64(aspect).inverse();
    let eye = frame.camera.eye.as_dvec3();
    let offsets: Vec<u32> = frame
        .triangles
        .iter()
        .scan(0u32, |acc, t| {
            let o = *acc;
            *acc += t.len() as u32;
            Some(o)
        })
        .collect();
    (0..w * h)
        .into_par_iter()
        .map(|i| {
            let [obj, tri] = frame.ids[i];
            if obj == 0 {
                return None;
            }
            let t = frame.triangles.get(obj as usize - 1)?.get(tri as usize)?;
            let t = [t[0].as_dvec3(), t[1].as_dvec3(), t[2].as_dvec3()];
            let (x, y) = ((i % w) as f64 + 0.5, (i / w) as f64 + 0.5);
            let ndc = DVec4::new(x / w as f64 * 2.0 - 1.0, 1.0 - y / h as f64 * 2.0, 0.5, 1.0);
            let p = inv * ndc;
            let dir = p.truncate() / p.w - eye;
            let mut n = (t[1] - t[0]).cross(t[2] - t[0]);
            let denom = n.dot(dir);
            let position = if denom != 0.0 && denom.is_finite() {
                eye + dir * (n.dot(t[0] - eye) / denom)
            } else {
                (t[0] + t[1] + t[2]) / 3.0
            };
            if n.dot(eye - position) < 0.0 {
                n = -n;
            }
            Some(SurfacePoint {
                position,
                normal: n,
                triangle: offsets[obj as usize - 1] + tri,
                albedo: frame
                    .albedo
                    .get(obj as usize - 1)
                    .map_or(1.0, |a| a[0].max(a[1]).max(a[2])),
            })
        })
        .collect()
}

/// The vector from `p` to the light: towards the light for a directional light (`w = 0`), and
/// exactly to the light's position `xyz / w` for a point light, so that the shadow segment
/// `p + t·v`, `t ∈ (0, 1)`, ends at the light for every `w > 0` (not only `w = 1`).
fn light_vec(l: [f32; 4], p: DVec3) -> DVec3 {
    let xyz = DVec3::new(f64::from(l[0]), f64::from(l[1]), f64::from(l[2]));
    let w = f64::from(l[3]);
    if w == 0.0 {
        xyz
    } else {
        xyz / w - p
    }
}

/// True when light `li` of `frame` visibly lights the surface point: the Lambert term
/// `albedo × intensity × attenuation × cos θ` is at least one 8-bit step (1/255), with the
/// attenuation of the light's emission ([`light_attenuation`]). Below that, lit and shadowed
/// give the same 8-bit pixel, so the state is invisible (and, for faces edge-on to the light,
/// ill-posed for the raster and the ray caster alike); such pixels count as unlit on both sides.
#[must_use]
pub fn faces_light(frame: &Frame, sp: &SurfacePoint, li: usize) -> bool {
    let l = frame.lights[li].to_array();
    let v = light_vec(l, sp.position);
    let d = sp.normal.dot(v);
    let gain = f64::from(sp.albedo)
        * f64::from(frame.light_color[li].iter().copied().fold(0.0, f32::max))
        * light_attenuation(frame, sp, li);
    d > 0.0 && gain > 0.0 && d * gain * 255.0 >= sp.normal.length() * v.length()
}

/// True when the surface point faces light `li` at all (`cos θ > 0`), however dimly: the
/// geometric facing of DESIGN.md's literal metric, without the 8-bit visibility threshold of
/// [`faces_light`].
#[must_use]
pub fn faces_light_geometric(frame: &Frame, sp: &SurfacePoint, li: usize) -> bool {
    let l = frame.lights[li].to_array();
    sp.normal.dot(light_vec(l, sp.position)) > 0.0 && light_attenuation(frame, sp, li) > 0.0
}

/// The attenuation of light `li` at the surface point: range window, inverse square and cone
/// ([`shadowvol_scenes::Emission::attenuation`], in `f64`), 1 for a unit light.
#[must_use]
pub fn light_attenuation(frame: &Frame, sp: &SurfacePoint, li: usize) -> f64 {
    frame.emission.get(li).map_or(1.0, |e| {
        e.attenuation(frame.lights[li].to_array(), sp.position)
    })
}

/// The raster's per-light states (light-major), from the stencil and the facing
/// ([`faces_light`]).
#[must_use]
pub fn raster_states(frame: &Frame, points: &[Option<SurfacePoint>]) -> Vec<Vec<PixelState>> {
    raster_states_with(frame, points, faces_light)
}

/// The raster's per-light states with the geometric facing ([`faces_light_geometric`]).
#[must_use]
pub fn raster_states_geometric(
    frame: &Frame,
    points: &[Option<SurfacePoint>],
) -> Vec<Vec<PixelState>> {
    raster_states_with(frame, points, faces_light_geometric)
}

/// Lit where the stencil is 0 and `facing` holds.
fn raster_states_with(
    frame: &Frame,
    points: &[Option<SurfacePoint>],
    facing: fn(&Frame, &SurfacePoint, usize) -> bool,
) -> Vec<Vec<PixelState>> {
    frame
        .lights
        .iter()
        .enumerate()
        .map(|(li, _)| {
            points
                .iter()
                .zip(&frame.stencil[li])
                .map(|(p, &s)| match p {
                    None => PixelState::Background,
                    Some(sp) if s == 0 && facing(frame, sp, li) => PixelState::Lit,
                    Some(_) => PixelState::Unlit,
                })
                .collect()
        })
        .collect()
}

/// The reference's per-light states (light-major), by ray casting; lit needs [`faces_light`].
#[must_use]
pub fn reference_states(frame: &Frame, points: &[Option<SurfacePoint>]) -> Vec<Vec<PixelState>> {
    let geometric = reference_states_geometric(frame, points);
    visible_only(frame, points, geometric)
}

/// Turns geometric reference states into visible ones: a pixel the light can't visibly light
/// ([`faces_light`] false) is unlit.
fn visible_only(
    frame: &Frame,
    points: &[Option<SurfacePoint>],
    mut states: Vec<Vec<PixelState>>,
) -> Vec<Vec<PixelState>> {
    for (li, row) in states.iter_mut().enumerate() {
        for (state, p) in row.iter_mut().zip(points) {
            if let Some(sp) = p {
                if !faces_light(frame, sp, li) {
                    *state = PixelState::Unlit;
                }
            }
        }
    }
    states
}

/// The reference's per-light states by ray casting, with the geometric facing
/// ([`faces_light_geometric`]): every surface point with `cos θ > 0` is ray cast, and every caster
/// the shadow ray's BVH boxes reach is decided exactly ([`crate::occlusion`]): unlit when one
/// blocks, [`PixelState::Uncertain`] when none blocks but one is [`Crossing::Undecidable`], else
/// lit. The pixel's own triangle is skipped (the surface point lies on it).
#[must_use]
pub fn reference_states_geometric(
    frame: &Frame,
    points: &[Option<SurfacePoint>],
) -> Vec<Vec<PixelState>> {
    let mut tris: Vec<[DVec3; 3]> = Vec::new();
    let mut casters: Vec<Caster> = Vec::new();
    let mut raw: Vec<[glam::Vec3; 3]> = Vec::new();
    let mut ids = Vec::new();
    let mut next = 0u32;
    for (oi, obj) in frame.triangles.iter().enumerate() {
        for t in obj {
            if frame.casts_shadows[oi] {
                let c = Caster::new(*t);
                tris.push(c.v);
                casters.push(c);
                raw.push(*t);
                ids.push(next);
            }
            next += 1;
        }
    }
    let bvh = Bvh::build_with_ids(tris, ids.clone());
    let eye = frame.camera.eye.as_dvec3();
    frame
        .lights
        .iter()
        .enumerate()
        .map(|(li, light)| {
            let l = light.to_array();
            // Which side of each caster's plane the light is on (0: in it, never blocks).
            let sides: Vec<i8> = raw.par_iter().map(|t| light_side(*t, l)).collect();
            let t_max = if l[3] == 0.0 { f64::INFINITY } else { 1.0 };
            points
                .par_iter()
                .map(|p| match p {
                    None => PixelState::Background,
                    Some(sp) => {
                        if !faces_light_geometric(frame, sp, li) {
                            return PixelState::Unlit;
                        }
                        let ray = ShadowRay::new(sp.position, l, eye);
                        let mut undecidable = false;
                        let blocked =
                            bvh.visit(sp.position, light_vec(l, sp.position), t_max, |i| {
                                if ids[i] == sp.triangle {
                                    return false;
                                }
                                match ray.crossing(&casters[i], sides[i]) {
                                    Crossing::Blocks => true,
                                    Crossing::Clear => false,
                                    Crossing::Undecidable => {
                                        undecidable = true;
                                        false
                                    }
                                }
                            });
                        if blocked {
                            PixelState::Unlit
                        } else if undecidable {
                            PixelState::Uncertain
                        } else {
                            PixelState::Lit
                        }
                    }
                })
                .collect()
        })
        .collect()
}

/// The comparison of a frame with the reference.
#[derive(Debug, Clone)]
pub struct Comparison {
    /// Pixels whose state differs from the reference for some light and that lie more than one
    /// pixel from a reference boundary of that light.
    pub artifact_pixels: usize,
    /// `artifact_pixels` with the geometric facing ([`faces_light_geometric`]): lit means the
    /// light reaches a surface with `cos θ > 0`, however dimly, without the 1/255 visibility
    /// threshold. DESIGN.md's definition read literally; differences here that are not in
    /// `artifact_pixels` are invisible in the 8-bit image.
    pub geometric_artifact_pixels: usize,
    /// Pixels whose state differs for some light (boundaries included), or where the reference
    /// is [`PixelState::Uncertain`].
    pub differing_pixels: usize,
    /// Covered pixels where the reference could not decide some light
    /// ([`PixelState::Uncertain`]; see [`crate::occlusion`] for the one case that remains) and
    /// that are not artifacts for another light.
    pub undecidable_pixels: usize,
    /// Pixels where raster and reference differ for some light but the reference's own state
    /// changes within the pixel's 3×3 neighbourhood (within one pixel of a reference shadow
    /// boundary), that are neither artifacts nor undecidable: not counted as artifacts.
    pub boundary_pixels: usize,
    /// Covered pixels the raster shadows (stencil ≠ 0 on a surface facing the light) for some
    /// light.
    pub shadow_pixels: usize,
    /// The same count from the reference.
    pub reference_shadow_pixels: usize,
    /// Covered pixels.
    pub covered_pixels: usize,
    /// Per pixel: 0 agree, 1 differs near a boundary or the reference is uncertain (not
    /// counted), 2 artifact: raster lit where
    /// the reference is shadowed, 3 artifact: raster shadowed where the reference is lit.
    pub classes: Vec<u8>,
}

impl Comparison {
    /// `artifact_pixels` as a fraction of all pixels.
    #[must_use]
    pub fn artifact_fraction(&self, total_pixels: usize) -> f64 {
        self.artifact_pixels as f64 / total_pixels.max(1) as f64
    }

    /// The share of covered pixels the metric checked: covered pixels that are neither
    /// [`Comparison::boundary_pixels`] nor [`Comparison::undecidable_pixels`] (1 when nothing is
    /// covered).
    #[must_use]
    pub fn checked_fraction(&self) -> f64 {
        if self.covered_pixels == 0 {
            return 1.0;
        }
        let left_out = self.boundary_pixels + self.undecidable_pixels;
        self.covered_pixels.saturating_sub(left_out) as f64 / self.covered_pixels as f64
    }
}

/// Counts the raster's shadowed pixels (stencil ≠ 0 on a surface facing the light, any light).
#[must_use]
pub fn shadow_pixels(frame: &Frame) -> usize {
    let points = surface_points(frame);
    count_shadowed(frame, &points, &raster_states(frame, &points))
}

fn count_shadowed(
    frame: &Frame,
    points: &[Option<SurfacePoint>],
    states: &[Vec<PixelState>],
) -> usize {
    (0..points.len())
        .filter(|&i| {
            let Some(sp) = points[i] else { return false };
            (0..frame.lights.len())
                .any(|li| faces_light(frame, &sp, li) && states[li][i] == PixelState::Unlit)
        })
        .count()
}

/// Per pixel, the worst class over the lights (see [`Comparison::classes`]), and whether the
/// reference is [`PixelState::Uncertain`] for some light.
fn classify(
    raster: &[Vec<PixelState>],
    reference: &[Vec<PixelState>],
    w: usize,
    h: usize,
) -> (Vec<u8>, Vec<bool>) {
    let mut classes = vec![0u8; w * h];
    let mut uncertain = vec![false; w * h];
    for (r, f) in raster.iter().zip(reference) {
        for i in 0..w * h {
            if f[i] == PixelState::Uncertain {
                classes[i] = classes[i].max(1);
                uncertain[i] = true;
                continue;
            }
            if r[i] == f[i] {
                continue;
            }
            let (x, y) = (i % w, i / w);
            let mut uniform = true;
            for ny in y.saturating_sub(1)..=(y + 1).min(h - 1) {
                for nx in x.saturating_sub(1)..=(x + 1).min(w - 1) {
                    if f[ny * w + nx] != f[i] {
                        uniform = false;
                    }
                }
            }
            let class = if !uniform {
                1
            } else if r[i] == PixelState::Lit {
                2
            } else {
                3
            };
            classes[i] = classes[i].max(class);
        }
    }
    (classes, uncertain)
}

/// Renders the reference and compares, with the visible facing ([`faces_light`]) for
/// `artifact_pixels` and the geometric one for `geometric_artifact_pixels`.
#[must_use]
pub fn compare(frame: &Frame) -> Comparison {
    let points = surface_points(frame);
    let (w, h) = (frame.width as usize, frame.height as usize);
    let raster_geometric = raster_states_geometric(frame, &points);
    let reference_geometric = reference_states_geometric(frame, &points);
    let (geometric, _) = classify(&raster_geometric, &reference_geometric, w, h);
    let raster = raster_states(frame, &points);
    let reference = visible_only(frame, &points, reference_geometric);
    let (classes, uncertain) = classify(&raster, &reference, w, h);
    let undecidable_pixels = classes
        .iter()
        .zip(&uncertain)
        .filter(|&(&c, &u)| u && c == 1)
        .count();
    Comparison {
        artifact_pixels: classes.iter().filter(|&&c| c >= 2).count(),
        geometric_artifact_pixels: geometric.iter().filter(|&&c| c >= 2).count(),
        differing_pixels: classes.iter().filter(|&&c| c >= 1).count(),
        undecidable_pixels,
        boundary_pixels: classes
            .iter()
            .zip(&uncertain)
            .filter(|&(&c, &u)| !u && c == 1)
            .count(),
        shadow_pixels: count_shadowed(frame, &points, &raster),
        reference_shadow_pixels: count_shadowed(frame, &points, &reference),
        covered_pixels: points.iter().filter(|p| p.is_some()).count(),
        classes,
    }
}

/// How well the image's colours match the lighting model where raster and reference agree.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct ShadingCheck {
    /// Pixels compared: covered, and every light's state the same in raster and reference.
    pub compared: usize,
    /// Of those, pixels with a channel more than the tolerance away from the prediction.
    pub mismatched: usize,
    /// The largest channel difference seen, in 8-bit steps.
    pub max_error: u8,
}

/// Predicts every compared pixel's colour from the lighting model in `f64` (the pre-pass's
/// `albedo × ambient`, plus per light whose state is lit `albedo × colour × attenuation ×
/// cos θ`, [`light_attenuation`]) and compares it with the 8-bit image, channel by channel, to
/// within `tolerance` steps. Pixels where raster and reference disagree (`cmp.classes != 0`) are
/// left out: the artifact metric counts them.
///
/// # Panics
/// Panics if `cmp` was not computed from `frame`.
#[must_use]
pub fn shading_check(frame: &Frame, cmp: &Comparison, tolerance: u8) -> ShadingCheck {
    let points = surface_points(frame);
    let raster = raster_states(frame, &points);
    let mut out = ShadingCheck::default();
    for (i, sp) in points.iter().enumerate() {
        let Some(sp) = sp else { continue };
        if cmp.classes[i] != 0 {
            continue;
        }
        let albedo = frame.albedo[frame.ids[i][0] as usize - 1];
        let mut c = albedo.map(|a| f64::from(a) * f64::from(frame.ambient));
        for (li, light) in frame.lights.iter().enumerate() {
            if raster[li][i] != PixelState::Lit {
                continue;
            }
            let v = light_vec(light.to_array(), sp.position);
            let cos = sp.normal.dot(v) / (sp.normal.length() * v.length());
            if cos > 0.0 {
                let k = cos * light_attenuation(frame, sp, li);
                for (ch, value) in c.iter_mut().enumerate() {
                    *value += f64::from(albedo[ch]) * f64::from(frame.light_color[li][ch]) * k;
                }
            }
        }
        out.compared += 1;
        let px = &frame.rgba[i * 4..i * 4 + 3];
        let err = (0..3)
            .map(|ch| {
                let want = (c[ch].clamp(0.0, 1.0) * 255.0).round() as i32;
                (want - i32::from(px[ch])).unsigned_abs()
            })
            .max()
            .unwrap_or(0);
        out.max_error = out.max_error.max(err.min(255) as u8);
        if err > u32::from(tolerance) {
            out.mismatched += 1;
        }
    }
    out
}

/// The disagreement as an image: the frame dimmed to grey, artifacts where the raster is lit
/// but the reference is shadowed in red, artifacts where the raster is shadowed but the reference
/// is lit in blue, boundary-only differences in yellow.
///
/// # Panics
/// Panics if `cmp` was not computed from `frame`.
#[must_use]
pub fn diff_image(frame: &Frame, cmp: &Comparison) -> image::RgbaImage {
    let mut img = frame.image();
    for (i, px) in img.pixels_mut().enumerate() {
        let g = ((u16::from(px[0]) + u16::from(px[1]) + u16::from(px[2])) / 6) as u8;
        *px = match cmp.classes[i] {
            0 => image::Rgba([g, g, g, 255]),
            1 => image::Rgba([230, 200, 40, 255]),
            2 => image::Rgba([255, 30, 30, 255]),
            _ => image::Rgba([40, 90, 255, 255]),
        };
    }
    img
}

/// Writes [`diff_image`] as a PNG.
///
/// # Errors
/// [`crate::RenderError::Image`] when the file cannot be written.
pub fn save_diff(
    frame: &Frame,
    cmp: &Comparison,
    path: impl AsRef<std::path::Path>,
) -> Result<(), crate::RenderError> {
    let p = path.as_ref();
    diff_image(frame, cmp)
        .save_with_format(p, image::ImageFormat::Png)
        .map_err(|e| crate::RenderError::Image {
            path: p.display().to_string(),
            message: e.to_string(),
        })
}

#[cfg(test)]
mod tests {

    /// Regression: the shadow segment `p + t·v`, `t ∈ (0, 1)`, must end at the light for every
    /// `w > 0`; it used to end at `L.xyz - (w - 1)·p`, which is the light only for `w = 1`.
    #[test]
    fn shadow_segment_ends_at_the_light_for_any_w() {
        let p = DVec3::new(0.5, -1.0, 0.25);
        for (l, light) in [
            ([0.0f32, 0.0, 4.0, 2.0], DVec3::new(0.0, 0.0, 2.0)),
            ([3.0, 1.5, -6.0, 0.75], DVec3::new(4.0, 2.0, -8.0)),
            ([1.0, 2.0, 3.0, 1.0], DVec3::new(1.0, 2.0, 3.0)),
        ] {
            let end = p + super::light_vec(l, p);
            assert!(
                (end - light).length() < 1e-12,
                "{l:?}: ends at {end}, light at {light}"
            );
        }
        // Directional: the direction towards the light, whatever the point.
        assert_eq!(
            super::light_vec([1.0, 2.0, 3.0, 0.0], p),
            DVec3::new(1.0, 2.0, 3.0)
        );
    }
    use super::*;

    #[test]
    fn bvh_matches_brute_force() {
        // A grid of small triangles; rays from below to above.
        let mut tris = Vec::new();
        for i in 0..20 {
            for j in 0..20 {
                let o = DVec3::new(f64::from(i), f64::from(j), f64::from((i * 7 + j * 3) % 5));
                tris.push([o, o + DVec3::X * 0.8, o + DVec3::Y * 0.8]);
            }
        }
        let bvh = Bvh::build(tris.clone());
        for k in 0..200 {
            let o = DVec3::new(
                f64::from(k % 20) + 0.1 + f64::from(k % 7) * 0.05,
                f64::from(k / 10) * 0.5,
                -1.0,
            );
            let d = DVec3::new(0.01 * f64::from(k % 3), 0.02, 10.0);
            let brute = tris
                .iter()
                .any(|t| intersect(t, o, d).is_some_and(|t| t > 0.0 && t < 1.0));
            assert_eq!(bvh.occluded(o, d, 0.0, 1.0, u32::MAX), brute, "ray {k}");
        }
    }
}
