//! Procedural meshes: spheres with an exact triangle count, Loop subdivision, the "town".
//!
//! All generators are deterministic (no randomness, no dependence on the platform's `sin`/`cos`
//! beyond `f64` rounding) and produce indexed meshes whose shared vertices have one index, so
//! the meshes are closed 2-manifolds where they should be.

use glam::{DVec3, Vec3};
use shadowvol_mesh_topology::{weld, Mesh};
use std::collections::HashMap;

/// The closest even triangle count to `target` (a closed triangle mesh has an even count), at
/// least `min`.
fn even_target(target: usize, min: usize) -> usize {
    let t = target.max(min);
    t + (t & 1)
}

/// A UV sphere (latitude/longitude grid) of radius `radius` centred at the origin, with
/// **exactly** `target` triangles when `target` is even and at least 12 (an odd `target` is
/// rounded up to the next even number, smaller ones to 12, the smallest UV sphere).
///
/// The grid has `slices` segments around the `Y` axis and `stacks` bands from pole to pole
/// (triangle fans at the poles): `2 · slices · (stacks − 1)` triangles. The grid closest to the
/// square-cell aspect `slices ≈ 2 (stacks − 1)` whose count does not exceed the target is chosen;
/// the remainder (fewer than `2 (stacks − 1)` triangles) is made up by splitting the diagonals of
/// evenly spread quads (each split turns 2 triangles into 4), with the new vertex on the sphere.
/// The result is a closed 2-manifold.
#[must_use]
pub fn uv_sphere(target: usize, radius: f32) -> Mesh {
    let t = even_target(target, 12);
    let half = t / 2; // = slices * (stacks - 1) + splits
                      // m = stacks - 1 (>= 2 so that there is at least one quad band), slices >= 3.
    let ideal = ((half as f64) / 2.0).sqrt().max(2.0);
    let mut best: Option<(usize, usize, f64)> = None; // (slices, m, score)
    let lo = ((ideal * 0.7).floor() as usize).max(2);
    let hi = ((ideal * 1.4).ceil() as usize).max(lo);
    // The preferred aspect range first, then every grid (only matters for tiny targets).
    for m in (lo..=hi).chain(2..=(half / 3).max(2)) {
        if best.is_some() && !(lo..=hi).contains(&m) {
            break;
        }
        let slices = half / m;
        if slices < 3 {
            continue;
        }
        let remainder = half - slices * m; // splits needed
        let quads = slices * (m - 1);
        if remainder > quads {
            continue;
        }
        let aspect = ((slices as f64) / (2.0 * m as f64)).ln().abs();
        let score = remainder as f64 / half as f64 * 50.0 + aspect;
        if best.is_none_or(|b| score < b.2) {
            best = Some((slices, m, score));
        }
    }
    let (slices, m) = best.map_or((3, 2), |b| (b.0, b.1));
    let splits = half - slices * m;
    let stacks = m + 1;
    let r = f64::from(radius);
    let mut positions = Vec::with_capacity(2 + slices * m + splits);
    positions.push(Vec3::new(0.0, radius, 0.0));
    for k in 1..stacks {
        let theta = std::f64::consts::PI * k as f64 / stacks as f64;
        let (st, ct) = theta.sin_cos();
        for s in 0..slices {
            let phi = std::f64::consts::TAU * s as f64 / slices as f64;
            let (sp, cp) = phi.sin_cos();
            positions.push(Vec3::new(
                (r * st * cp) as f32,
                (r * ct) as f32,
                (-r * st * sp) as f32,
            ));
        }
    }
    let south = positions.len() as u32;
    positions.push(Vec3::new(0.0, -radius, 0.0));
    let ring = |k: usize, s: usize| (1 + (k - 1) * slices + s % slices) as u32;
    let mut triangles = Vec::with_capacity(t);
    for s in 0..slices {
        triangles.push([0, ring(1, s), ring(1, s + 1)]);
    }
    // Quads of band k (between rings k and k+1), k = 1..stacks-1; pick evenly spread ones to split.
    let quad_count = slices * (m - 1);
    let mut split_at = vec![false; quad_count];
    for j in 0..splits {
        split_at[(j * quad_count + quad_count / 2) / splits.max(1) % quad_count.max(1)] = true;
    }
    let mut q = 0;
    for k in 1..m {
        for s in 0..slices {
            let (a, b, c, d) = (
                ring(k, s),
                ring(k + 1, s),
                ring(k + 1, s + 1),
                ring(k, s + 1),
            );
            if split_at[q] {
                let mid = (positions[a as usize].as_dvec3() + positions[c as usize].as_dvec3())
                    .normalize()
                    * r;
                let e = positions.len() as u32;
                positions.push(mid.as_vec3());
                triangles.extend([[a, b, e], [b, c, e], [c, d, e], [d, a, e]]);
            } else {
                triangles.extend([[a, b, c], [a, c, d]]);
            }
            q += 1;
        }
    }
    for s in 0..slices {
        triangles.push([south, ring(m, s + 1), ring(m, s)]);
    }
    debug_assert_eq!(triangles.len(), t);
    Mesh {
        positions,
        triangles,
    }
}

/// The 12 vertices and 20 faces of a regular icosahedron (counter-clockwise seen from outside).
fn icosahedron() -> ([DVec3; 12], [[usize; 3]; 20]) {
    let p = (1.0 + 5f64.sqrt()) / 2.0;
    let v = [
        DVec3::new(-1.0, p, 0.0),
        DVec3::new(1.0, p, 0.0),
        DVec3::new(-1.0, -p, 0.0),
        DVec3::new(1.0, -p, 0.0),
        DVec3::new(0.0, -1.0, p),
        DVec3::new(0.0, 1.0, p),
        DVec3::new(0.0, -1.0, -p),
        DVec3::new(0.0, 1.0, -p),
        DVec3::new(p, 0.0, -1.0),
        DVec3::new(p, 0.0, 1.0),
        DVec3::new(-p, 0.0, -1.0),
        DVec3::new(-p, 0.0, 1.0),
    ];
    let f = [
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    (v, f)
}

/// A geodesic icosphere of radius `radius` with **exactly** `target` triangles when `target` is
/// even and at least 320 (smaller targets get the closest count reachable, at least 20).
///
/// Each icosahedron face is divided with frequency `n` (`20 n²` triangles, the largest not above
/// the target); grid points are computed from their barycentric weights in a canonical order, so
/// points on shared icosahedron edges are bit-identical and get one index. The remainder is made
/// up by splitting the shared edge of evenly spread (up, down) triangle pairs, each split adding
/// two triangles. The result is a closed 2-manifold.
#[must_use]
pub fn icosphere(target: usize, radius: f32) -> Mesh {
    let t = even_target(target, 20);
    let mut n = ((t as f64 / 20.0).sqrt().floor() as usize).max(1);
    while 20 * (n + 1) * (n + 1) <= t {
        n += 1;
    }
    while n > 1 && 20 * n * n > t {
        n -= 1;
    }
    let rhombi = 20 * n * (n - 1) / 2;
    let splits = ((t - 20 * n * n) / 2).min(rhombi);
    let (v, faces) = icosahedron();
    let r = f64::from(radius);
    let mut map: HashMap<u64, u32> = HashMap::with_capacity(10 * n * n + 2);
    let mut positions: Vec<Vec3> = Vec::with_capacity(10 * n * n + 2 + splits);
    let mut point = |weights: [(usize, usize); 3], positions: &mut Vec<Vec3>| -> u32 {
        let mut w = weights;
        w.sort_unstable();
        let mut key = 0u64;
        let mut sum = DVec3::ZERO;
        for &(id, wt) in &w {
            if wt > 0 {
                key = key << 21 | (id as u64) << 16 | wt as u64;
                sum += v[id] * wt as f64;
            }
        }
        *map.entry(key).or_insert_with(|| {
            positions.push((sum.normalize() * r).as_vec3());
            (positions.len() - 1) as u32
        })
    };
    let mut triangles = Vec::with_capacity(t);
    let mut rhombus = 0usize;
    let mut next_split = 0usize;
    let split_index = |j: usize| (j * rhombi + rhombi / 2) / splits.max(1);
    for f in &faces {
        let mut grid = vec![0u32; (n + 1) * (n + 2) / 2];
        let at = |i: usize, j: usize| i * (2 * n + 3 - i) / 2 + j;
        for i in 0..=n {
            for j in 0..=n - i {
                grid[at(i, j)] = point([(f[0], n - i - j), (f[1], i), (f[2], j)], &mut positions);
            }
        }
        for i in 0..n {
            for j in 0..n - i {
                let (a, b, c) = (grid[at(i, j)], grid[at(i + 1, j)], grid[at(i, j + 1)]);
                if i + j + 1 < n {
                    let d = grid[at(i + 1, j + 1)];
                    if next_split < splits && split_index(next_split) == rhombus {
                        next_split += 1;
                        let mid = (positions[b as usize].as_dvec3()
                            + positions[c as usize].as_dvec3())
                        .normalize()
                            * r;
                        let e = positions.len() as u32;
                        positions.push(mid.as_vec3());
                        triangles.extend([[a, b, e], [a, e, c], [b, d, e], [e, d, c]]);
                    } else {
                        triangles.extend([[a, b, c], [b, d, c]]);
                    }
                    rhombus += 1;
                } else {
                    triangles.push([a, b, c]);
                }
            }
        }
    }
    Mesh {
        positions,
        triangles,
    }
}

/// One level of Loop subdivision (each triangle becomes four).
///
/// Vertices are first welded by exact position, so the result does not depend on how the input
/// was indexed. Interior edges (two triangles) use the `3/8, 3/8, 1/8, 1/8` rule, interior
/// vertices Warren's weights (`β = 3/16` for valence 3, else `3 / (8 n)`). Boundary and
/// non-manifold edges are creases: their new point is the midpoint, a vertex on exactly two
/// crease edges uses `3/4, 1/8, 1/8`, and a vertex on another number of crease edges stays put.
/// Arithmetic is in `f64`, rounded to `f32` once. Degenerate input triangles (a repeated
/// welded vertex) are dropped.
#[must_use]
pub fn loop_subdivide(mesh: &Mesh) -> Mesh {
    let w = weld(&mesh.positions);
    let pos: Vec<DVec3> = w.positions.iter().map(|p| p.as_dvec3()).collect();
    let tris: Vec<[u32; 3]> = mesh
        .triangles
        .iter()
        .map(|t| t.map(|i| w.compact_of_input[i as usize]))
        .filter(|t| t[0] != t[1] && t[1] != t[2] && t[0] != t[2])
        .collect();
    let nv = pos.len();
    // Edges: key (min, max) -> (edge id); per edge: endpoints, opposite-vertex sum and count.
    let mut edge_of: HashMap<(u32, u32), u32> = HashMap::with_capacity(tris.len() * 3 / 2 + 8);
    let mut ends: Vec<(u32, u32)> = Vec::with_capacity(tris.len() * 3 / 2 + 8);
    let mut opp_sum: Vec<DVec3> = Vec::with_capacity(tris.len() * 3 / 2 + 8);
    let mut opp_n: Vec<u32> = Vec::with_capacity(tris.len() * 3 / 2 + 8);
    let mut tri_edges = Vec::with_capacity(tris.len());
    for t in &tris {
        let mut te = [0u32; 3];
        for k in 0..3 {
            let (a, b, o) = (t[k], t[(k + 1) % 3], t[(k + 2) % 3]);
            let key = (a.min(b), a.max(b));
            let id = *edge_of.entry(key).or_insert_with(|| {
                ends.push(key);
                opp_sum.push(DVec3::ZERO);
                opp_n.push(0);
                (ends.len() - 1) as u32
            });
            opp_sum[id as usize] += pos[o as usize];
            opp_n[id as usize] += 1;
            te[k] = id;
        }
        tri_edges.push(te);
    }
    // Vertex rules.
    let mut nb_sum = vec![DVec3::ZERO; nv];
    let mut nb_n = vec![0u32; nv];
    let mut crease_sum = vec![DVec3::ZERO; nv];
    let mut crease_n = vec![0u32; nv];
    for (e, &(a, b)) in ends.iter().enumerate() {
        let (pa, pb) = (pos[a as usize], pos[b as usize]);
        nb_sum[a as usize] += pb;
        nb_sum[b as usize] += pa;
        nb_n[a as usize] += 1;
        nb_n[b as usize] += 1;
        if opp_n[e] != 2 {
            crease_sum[a as usize] += pb;
            crease_sum[b as usize] += pa;
            crease_n[a as usize] += 1;
            crease_n[b as usize] += 1;
        }
    }
    let mut positions = Vec::with_capacity(nv + ends.len());
    for v in 0..nv {
        let p = pos[v];
        let q = match (crease_n[v], nb_n[v]) {
            (_, 0) => p,
            (0, n) => {
                let beta = if n == 3 {
                    3.0 / 16.0
                } else {
                    3.0 / (8.0 * f64::from(n))
                };
                p * (1.0 - f64::from(n) * beta) + nb_sum[v] * beta
            }
            (2, _) => p * 0.75 + crease_sum[v] * 0.125,
            _ => p,
        };
        positions.push(q.as_vec3());
    }
    for (e, &(a, b)) in ends.iter().enumerate() {
        let (pa, pb) = (pos[a as usize], pos[b as usize]);
        let q = if opp_n[e] == 2 {
            (pa + pb) * 0.375 + opp_sum[e] * 0.125
        } else {
            (pa + pb) * 0.5
        };
        positions.push(q.as_vec3());
    }
    let base = nv as u32;
    let mut triangles = Vec::with_capacity(tris.len() * 4);
    for (t, te) in tris.iter().zip(&tri_edges) {
        let [a, b, c] = *t;
        let (ab, bc, ca) = (base + te[0], base + te[1], base + te[2]);
        triangles.extend([[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]);
    }
    Mesh {
        positions,
        triangles,
    }
}

/// `levels` levels of [`loop_subdivide`]: `4^levels` times the (non-degenerate) triangles.
#[must_use]
pub fn loop_subdivide_levels(mesh: &Mesh, levels: u32) -> Mesh {
    let mut m = mesh.clone();
    for _ in 0..levels {
        m = loop_subdivide(&m);
    }
    m
}

/// Parameters of the procedural town.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TownParams {
    /// Buildings per side of the square grid.
    pub grid: u32,
    /// Distance between building centres (world units; integer so coordinates stay exact).
    pub pitch: u32,
    /// Edge length of one wall panel (world units); footprints are whole panels.
    pub panel: u32,
    /// Height of one floor (world units).
    pub floor: u32,
}

impl Default for TownParams {
    /// The `town` preset: a 27 × 27 grid, 40 units apart, 4-unit panels and floors
    /// (about 570,000 triangles).
    fn default() -> Self {
        Self {
            grid: 27,
            pitch: 40,
            panel: 4,
            floor: 4,
        }
    }
}

/// A small deterministic integer hash (for building sizes).
fn hash(mut x: u32) -> u32 {
    x ^= x >> 16;
    x = x.wrapping_mul(0x7feb_352d);
    x ^= x >> 15;
    x = x.wrapping_mul(0x846c_a68b);
    x ^ (x >> 16)
}

/// Footprint `(panels x, floors, panels z)` of building `(gx, gz)`.
fn building_cells(p: &TownParams, gx: u32, gz: u32) -> (u32, u32, u32) {
    let h = hash(gx.wrapping_mul(7919) ^ gz.wrapping_mul(104_729) ^ 0x5bd1_e995);
    let max_cells = ((p.pitch * 3 / 4) / p.panel).max(2);
    let nx = 3 + (h % (max_cells - 2).max(1));
    let nz = 3 + ((h >> 8) % (max_cells - 2).max(1));
    let ny = 4 + ((h >> 16) % 27);
    (nx.min(max_cells), ny, nz.min(max_cells))
}

/// Triangles of a box subdivided into `nx × ny × nz` cells on its surface.
fn box_triangles(nx: u32, ny: u32, nz: u32) -> usize {
    4 * (nx as usize * ny as usize + ny as usize * nz as usize + nx as usize * nz as usize)
}

/// Triangle count of [`town`] with these parameters, without building it.
#[must_use]
pub fn town_triangle_count(p: &TownParams) -> usize {
    let mut total = 0;
    for gz in 0..p.grid {
        for gx in 0..p.grid {
            let (nx, ny, nz) = building_cells(p, gx, gz);
            total += box_triangles(nx, ny, nz);
        }
    }
    total
}

/// A procedural town: a `grid × grid` array of axis-aligned box buildings standing on `y = 0`,
/// each a closed box whose faces are subdivided into `panel × floor` wall panels (as window
/// grids are), so large planar regions are tessellated. All coordinates are integers, exact in
/// `f32`. With a sun exactly along `+Y` every wall triangle is exactly parallel to the light:
/// the hard case of Vyatkin's "Town" scene.
///
/// # Panics
/// Panics if `grid`, `pitch`, `panel` or `floor` is 0.
#[must_use]
pub fn town(p: &TownParams) -> Mesh {
    assert!(
        p.grid > 0 && p.pitch > 0 && p.panel > 0 && p.floor > 0,
        "town parameters must be positive: {p:?}"
    );
    let total = town_triangle_count(p);
    let mut mesh = Mesh {
        positions: Vec::with_capacity(total / 2 + 2 * (p.grid * p.grid) as usize),
        triangles: Vec::with_capacity(total),
    };
    let half = (p.grid * p.pitch / 2) as i64;
    for gz in 0..p.grid {
        for gx in 0..p.grid {
            let (nx, ny, nz) = building_cells(p, gx, gz);
            let cx = i64::from(gx * p.pitch + p.pitch / 2) - half;
            let cz = i64::from(gz * p.pitch + p.pitch / 2) - half;
            let x0 = cx - i64::from(nx * p.panel / 2);
            let z0 = cz - i64::from(nz * p.panel / 2);
            add_box(
                &mut mesh,
                [x0, 0, z0],
                [i64::from(p.panel), i64::from(p.floor), i64::from(p.panel)],
                [nx, ny, nz],
            );
        }
    }
    mesh
}

/// Appends a closed box with corner `origin`, cell size `cell` and `cells` cells per axis, its
/// six faces tessellated into the cell grid, outward winding, shared vertices indexed once.
fn add_box(mesh: &mut Mesh, origin: [i64; 3], cell: [i64; 3], cells: [u32; 3]) {
    let [nx, ny, nz] = cells.map(|c| c as i64);
    let mut index: HashMap<(i64, i64, i64), u32> = HashMap::new();
    let mut vid = |mesh: &mut Mesh, i: i64, j: i64, k: i64| -> u32 {
        *index.entry((i, j, k)).or_insert_with(|| {
            mesh.positions.push(Vec3::new(
                (origin[0] + i * cell[0]) as f32,
                (origin[1] + j * cell[1]) as f32,
                (origin[2] + k * cell[2]) as f32,
            ));
            (mesh.positions.len() - 1) as u32
        })
    };
    // Each face: fixed axis and value, two running axes (u, v) oriented so that u × v points out.
    // (axis fixed, value, u axis, v axis, nu, nv)
    let faces: [(usize, i64, usize, usize); 6] = [
        (0, 0, 2, 1),  // -X: u = z, v = y -> z × y = -x
        (0, nx, 1, 2), // +X: y × z = +x
        (1, 0, 0, 2),  // -Y: x × z = -y
        (1, ny, 2, 0), // +Y: z × x = +y
        (2, 0, 1, 0),  // -Z: y × x = -z
        (2, nz, 0, 1), // +Z: x × y = +z
    ];
    let n = [nx, ny, nz];
    for (axis, value, ua, va) in faces {
        for u in 0..n[ua] {
            for v in 0..n[va] {
                let mut corner = |du: i64, dv: i64| {
                    let mut c = [0i64; 3];
                    c[axis] = value;
                    c[ua] = u + du;
                    c[va] = v + dv;
                    vid(mesh, c[0], c[1], c[2])
                };
                let (a, b, c, d) = (corner(0, 0), corner(1, 0), corner(1, 1), corner(0, 1));
                mesh.triangles.extend([[a, b, c], [a, c, d]]);
            }
        }
    }
}
