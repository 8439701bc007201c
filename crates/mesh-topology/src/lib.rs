//! Triangle meshes and the edge topology that silhouette extraction runs on.
//!
//! The pipeline is `Mesh` → [`weld`] → [`EdgeTable`]:
//!
//! * [`Mesh`] holds `f32` positions and `u32` triangles exactly as they were loaded.
//! * [`weld`] merges vertices whose positions are bit-for-bit equal (with `-0.0 == +0.0`). A weld
//!   group is named by its smallest input index, and compact (welded) ids are assigned in
//!   ascending order of that name, so ordering by compact id is ordering by name.
//! * [`EdgeTable::build`] drops triangles that are degenerate after welding (a repeated vertex),
//!   and lists every undirected edge `(a, b)` with `a < b` once, together with the *opposite
//!   vertices* (OVs) of all triangles that share it, in compressed-sparse-row form. Any number of
//!   triangles per edge is allowed: boundary (1), manifold (2) and non-manifold (3 or more).
//!
//! Construction is linear in the number of triangles: a counting sort buckets the edge entries by
//! their smaller endpoint and each (small) bucket is sorted by the larger one.
//!
//! ```
//! use shadowvol_mesh_topology::{EdgeTable, Mesh};
//! use glam::Vec3;
//!
//! // A tetrahedron: closed and manifold.
//! let mesh = Mesh::new(
//!     vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z],
//!     vec![[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]],
//! )?;
//! let table = EdgeTable::build(&mesh)?;
//! assert_eq!(table.stats.edges, 6);
//! assert_eq!(table.stats.manifold_edges, 6);
//! assert_eq!(table.ovs_of(0).len(), 2);
//! # Ok::<(), shadowvol_mesh_topology::MeshError>(())
//! ```

mod edge_table;
mod error;
mod memory;
mod mesh;
mod renumbering;
mod welding;

pub use edge_table::{EdgeTable, MeshStats, NO_EDGE, NO_NEIGHBOR};
pub use error::MeshError;
pub use memory::{
    available_memory, unique_arc_bytes, vec_bytes, MEMORY_CHECK_THRESHOLD, MEMORY_LIMIT_ENV,
};
pub use mesh::Mesh;
pub use renumbering::Renumbering;
pub use welding::{positions_distinct, positions_distinct_by, weld, SoupWeld, Weld};

/// Peak-allocation tracking for the estimate tests: a global allocator that counts each
/// thread's live bytes (only in this crate's unit-test binary).
#[cfg(test)]
mod counting {
    // The counts are per thread: the test harness runs tests on parallel threads, and a
    // process-wide count let one test's allocations show up in another's peak (seen in CI: a
    // 9834-byte "peak" in a test that allocates nothing). Nothing measured here spawns threads.
    use std::alloc::{GlobalAlloc, Layout, System};
    use std::cell::Cell;

    pub struct Counting;

    thread_local! {
        // Const-initialised, no destructor: reading them never allocates.
        static LIVE: Cell<isize> = const { Cell::new(0) };
        static PEAK: Cell<isize> = const { Cell::new(0) };
    }

    // SAFETY: forwards to the system allocator; only counts.
    unsafe impl GlobalAlloc for Counting {
        unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
            let size = layout.size() as isize;
            // `try_with`: during thread teardown the counters may be gone; then nothing counts.
            let _ = LIVE.try_with(|live| {
                live.set(live.get() + size);
                let _ = PEAK.try_with(|peak| peak.set(peak.get().max(live.get())));
            });
            // SAFETY: same contract as the caller's.
            unsafe { System.alloc(layout) }
        }
        unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
            let size = layout.size() as isize;
            let _ = LIVE.try_with(|live| live.set(live.get() - size));
            // SAFETY: same contract as the caller's.
            unsafe { System.dealloc(ptr, layout) }
        }
    }

    #[global_allocator]
    static GLOBAL: Counting = Counting;

    /// Peak live bytes allocated by this thread above its level at the start, while `f` runs.
    pub fn peak_during<R>(f: impl FnOnce() -> R) -> (R, usize) {
        let base = LIVE.with(Cell::get);
        PEAK.with(|p| p.set(base));
        let r = f();
        let peak = PEAK.with(Cell::get);
        (r, usize::try_from(peak - base).unwrap_or(0))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::welding::{weld_hash, weld_key};
    use glam::Vec3;

    /// An `n x n` grid of quads (2 n^2 triangles, manifold inside, boundary around).
    fn grid(n: u32) -> Mesh {
        let mut positions = Vec::new();
        for y in 0..=n {
            for x in 0..=n {
                positions.push(Vec3::new(x as f32, y as f32, ((x * 7 + y * 3) % 5) as f32));
            }
        }
        let mut triangles = Vec::new();
        let id = |x: u32, y: u32| y * (n + 1) + x;
        for y in 0..n {
            for x in 0..n {
                triangles.push([id(x, y), id(x + 1, y), id(x + 1, y + 1)]);
                triangles.push([id(x, y), id(x + 1, y + 1), id(x, y + 1)]);
            }
        }
        Mesh::new(positions, triangles).unwrap()
    }

    /// A soup: every triangle has its own three vertices (3 boundary edges per triangle, the
    /// most edges a mesh can have).
    fn soup(t: u32) -> Mesh {
        let mut positions = Vec::new();
        let mut triangles = Vec::new();
        for i in 0..t {
            let f = i as f32;
            positions.extend([
                Vec3::new(f, 0.0, 0.0),
                Vec3::new(f, 1.0, 0.0),
                Vec3::new(f, 0.0, 1.0),
            ]);
            triangles.push([3 * i, 3 * i + 1, 3 * i + 2]);
        }
        Mesh::new(positions, triangles).unwrap()
    }

    #[test]
    fn estimate_bounds_the_measured_peak_allocation() {
        for (name, mesh) in [("grid", grid(300)), ("soup", soup(150_000))] {
            let t = mesh.triangles.len() as u64;
            let v = mesh.positions.len() as u64;
            let estimate = EdgeTable::estimate_bytes(t, v);
            // The counts are per thread: build on a pool of one thread, inside it, so that
            // every allocation of the parallel steps is counted.
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(1)
                .build()
                .unwrap();
            let (table, peak) =
                pool.install(|| counting::peak_during(|| EdgeTable::build(&mesh).unwrap()));
            assert_eq!(table.stats.triangles, mesh.triangles.len());
            let peak = peak as u64;
            eprintln!("{name}: {t} triangles, {v} vertices: peak {peak} B, estimate {estimate} B");
            assert!(
                peak <= estimate,
                "{name}: peak {peak} > estimate {estimate}"
            );
            // Not uselessly loose either.
            assert!(
                2 * peak >= estimate,
                "{name}: peak {peak} is under half of {estimate}"
            );
        }
    }

    #[test]
    fn beyond_u32_is_refused_without_allocating() {
        let ((), peak) = counting::peak_during(|| {
            let e = EdgeTable::check_size(1 << 31, 10).unwrap_err();
            assert!(matches!(
                e,
                MeshError::TooLarge {
                    what: "opposite-vertex references (4 x triangles)",
                    ..
                }
            ));
            assert!(e.to_string().contains("8589934592"), "{e}");
            let e = EdgeTable::check_size(10, u64::from(u32::MAX)).unwrap_err();
            assert!(
                matches!(
                    e,
                    MeshError::TooLarge {
                        what: "vertices",
                        ..
                    }
                ),
                "{e}"
            );
        });
        assert!(peak < 4096, "{peak} bytes allocated");
        // Just inside the limit passes the index check (the memory check may still refuse).
        let inside = EdgeTable::check_size((u64::from(u32::MAX) - 1) / 4, 3);
        assert!(
            !matches!(inside, Err(MeshError::TooLarge { .. })),
            "{inside:?}"
        );
    }

    #[test]
    fn memory_check_names_the_numbers() {
        // 10^12 triangles fits no machine this runs on (1.66e14 bytes); vertices stay in range
        // but triangles don't: use a count inside u32 and a huge vertex count instead.
        let Some((available, _)) = available_memory() else {
            return; // not Linux: nothing to compare against
        };
        let t = (u64::from(u32::MAX) - 1) / 4;
        let v = u64::from(u32::MAX) - 2;
        let needed = EdgeTable::estimate_bytes(t, v);
        if needed <= available {
            return; // a machine with over 500 GB free
        }
        let e = EdgeTable::check_size(t, v).unwrap_err();
        let msg = e.to_string();
        assert!(matches!(e, MeshError::OutOfMemory { .. }), "{msg}");
        assert!(
            msg.contains(&needed.to_string()) && msg.contains("MiB"),
            "{msg}"
        );
        assert!(
            msg.contains(&t.to_string()) && msg.contains(&v.to_string()),
            "{msg}"
        );
    }

    /// The parallel weld and grouping on meshes large enough to split into many chunks, with
    /// many duplicates racing for one group: the same result as the definition (names are
    /// first occurrences, ids in their order) and as a build on one thread.
    #[test]
    fn parallel_build_matches_the_definition_and_one_thread() {
        // 240,000 corners in a scrambled order, and a soup over them: the first 60,000 drawn
        // from 50 positions (edges of many triangles), the rest from 12,000 (several chunks of
        // vertices in the grouping).
        let distinct = |k: u32| Vec3::new((k % 30) as f32, (k / 30 % 30) as f32, (k / 900) as f32);
        let p: Vec<Vec3> = (0..240_000u32)
            .map(|i| {
                let h = i.wrapping_mul(2_654_435_761) >> 11;
                distinct(if i < 60_000 { h % 50 } else { h % 12_000 })
            })
            .collect();
        let w = weld(&p);
        let mut first = std::collections::HashMap::new();
        let names: Vec<u32> = (0..p.len() as u32)
            .map(|i| *first.entry(weld_key(p[i as usize])).or_insert(i))
            .collect();
        let mut distinct_names = names.clone();
        distinct_names.sort_unstable();
        distinct_names.dedup();
        assert_eq!(w.names, distinct_names);
        for (i, &n) in names.iter().enumerate() {
            let c = w.compact_of_input[i] as usize;
            assert_eq!(w.names[c], n, "vertex {i}");
            assert_eq!(w.positions[c], p[n as usize]);
        }
        let triangles: Vec<[u32; 3]> = (0..80_000u32)
            .map(|t| [3 * t, 3 * t + 1, 3 * t + 2])
            .collect();
        let mesh = Mesh::new(p, triangles).unwrap();
        let many = EdgeTable::build(&mesh).unwrap();
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap();
        let one = pool.install(|| EdgeTable::build(&mesh).unwrap());
        assert_eq!(many, one);
        // Independently of the grouping: each (edge, OV) pair names a kept triangle, and each
        // kept triangle is named once per edge.
        let canon = |mut t: [u32; 3]| {
            t.sort_unstable();
            t
        };
        let mut left: std::collections::HashMap<[u32; 3], i64> = std::collections::HashMap::new();
        for &t in &many.triangles {
            *left.entry(canon(t)).or_default() += 3;
        }
        for (e, &[a, b]) in many.edges.iter().enumerate() {
            for &r in many.ov_refs_of(e) {
                // Reference `4 t + rank`: triangle t is the edge's and the OV's, the OV has that
                // rank among its ids.
                let (t, rank) = ((r >> 2) as usize, (r & 3) as usize);
                let sorted = canon(many.triangles[t]);
                let o = sorted[rank];
                assert_eq!(canon([a, b, o]), sorted, "reference {r} of edge {e}");
                assert_eq!(EdgeTable::ov_odd(r), a < o && o < b);
                *left.entry(sorted).or_default() -= 1;
            }
        }
        assert!(
            left.values().all(|&n| n == 0),
            "OV lists disagree with the triangles"
        );
        assert!(
            many.stats.nonmanifold_edges > 0 && many.stats.boundary_edges > 0,
            "{:?}",
            many.stats
        );
    }

    #[test]
    fn weld_negative_zero_and_names() {
        let p = vec![
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
            Vec3::new(1.0, -0.0, 0.0),
            Vec3::new(0.0, 1.0, -0.0),
            Vec3::new(2.0, 0.0, 0.0),
        ];
        let w = weld(&p);
        assert_eq!(w.names, vec![0, 1, 4]);
        assert_eq!(w.compact_of_input, vec![0, 1, 0, 1, 2]);
    }

    /// Linear probing wraps from the table's last slot to slot 0 (a table of 16 slots for up
    /// to 8 vertices): keys that hash to slot 15 and to slot 0 collide across the wrap.
    #[test]
    fn weld_probing_wraps_around_the_table() {
        let find = |slot: usize, n: usize| -> Vec<Vec3> {
            (0..)
                .map(|i| Vec3::new(i as f32, 0.5, -2.0))
                .filter(|&p| weld_hash(weld_key(p), 4) == slot)
                .take(n)
                .collect()
        };
        let (last, first) = (find(15, 3), find(0, 2));
        let p = vec![
            last[0], last[1], first[0], last[2], last[0], first[1], last[1], first[0],
        ];
        assert_eq!(p.len(), 8, "8 vertices: 16 slots");
        let w = weld(&p);
        // The reference: a group is named by its first index, compact ids in order of names.
        let names: Vec<u32> = (0..p.len())
            .map(|i| (0..=i).find(|&j| p[j] == p[i]).unwrap() as u32)
            .collect();
        let mut distinct = names.clone();
        distinct.sort_unstable();
        distinct.dedup();
        assert_eq!(w.names, distinct);
        assert_eq!(w.names, vec![0, 1, 2, 3, 5]);
        for (i, &c) in w.compact_of_input.iter().enumerate() {
            assert_eq!(w.names[c as usize], names[i], "vertex {i}");
            assert_eq!(w.positions[c as usize], p[i]);
        }
    }

    #[test]
    fn shared_tables_are_counted_once() {
        let a = std::sync::Arc::new(EdgeTable::build(&grid(10)).unwrap());
        let b = std::sync::Arc::new(EdgeTable::build(&grid(20)).unwrap());
        let items = [a.clone(), b.clone(), a.clone(), a.clone()];
        assert_eq!(
            unique_arc_bytes(&items, EdgeTable::heap_bytes),
            a.heap_bytes() + b.heap_bytes()
        );
        assert!(a.heap_bytes() >= vec_bytes(&a.ov_refs) + vec_bytes(&a.edges));
    }

    /// A mesh with a duplicate vertex (-0.0 against +0.0) and a triangle degenerate after
    /// welding, so that compaction drops one and renumbers the rest.
    fn duplicate_and_degenerate() -> Mesh {
        Mesh {
            positions: vec![
                Vec3::ZERO,
                Vec3::X,
                Vec3::Y,
                Vec3::new(-0.0, 0.0, 0.0),
                Vec3::Z,
            ],
            triangles: vec![[0, 1, 2], [3, 1, 4], [0, 3, 2], [1, 2, 4], [4, 2, 3]],
        }
    }

    /// The soup of `mesh`: triangle `t` over its own vertices `3 t .. 3 t + 3`.
    fn as_soup(mesh: &Mesh) -> Mesh {
        let positions: Vec<Vec3> = mesh
            .triangles
            .iter()
            .flat_map(|t| t.map(|v| mesh.positions[v as usize]))
            .collect();
        let n = mesh.triangles.len() as u32;
        Mesh::new(
            positions,
            (0..n).map(|t| [3 * t, 3 * t + 1, 3 * t + 2]).collect(),
        )
        .unwrap()
    }

    #[test]
    fn a_soup_welded_as_read_makes_the_table_build_makes() {
        // Shared corners, -0.0 against +0.0, a facet degenerate after welding, and enough
        // distinct positions to grow the index table several times.
        let dup = duplicate_and_degenerate();
        for mesh in [grid(40), soup(500), dup] {
            let soup = as_soup(&mesh);
            let built = EdgeTable::build(&soup).unwrap();
            let mut w = SoupWeld::new();
            let tris: Vec<[u32; 3]> = soup
                .triangles
                .iter()
                .map(|t| t.map(|v| w.push(soup.positions[v as usize])))
                .collect();
            assert_eq!(w.pushed(), soup.positions.len() as u64);
            assert_eq!(EdgeTable::from_soup_weld(w, tris).unwrap(), built);
        }
        let mut w = SoupWeld::new();
        w.push(Vec3::ZERO);
        assert!(matches!(
            EdgeTable::from_soup_weld(w, vec![[0, 0, 1]]),
            Err(MeshError::IndexOutOfRange {
                corner: 2,
                index: 1,
                vertices: 1,
                ..
            })
        ));
    }

    #[test]
    fn build_owned_makes_the_table_build_makes() {
        // A grid, a soup, and a mesh with a duplicate vertex (-0.0) and a triangle degenerate
        // after welding, so that compaction drops one and renumbers the rest.
        let dup = duplicate_and_degenerate();
        for mesh in [grid(40), soup(500), dup] {
            let built = EdgeTable::build(&mesh).unwrap();
            let owned = EdgeTable::build_owned(mesh).unwrap();
            assert_eq!(owned, built);
        }
        assert_eq!(
            EdgeTable::build_owned(Mesh {
                positions: vec![Vec3::ZERO],
                triangles: vec![[0, 0, 3]],
            })
            .unwrap_err(),
            EdgeTable::build(&Mesh {
                positions: vec![Vec3::ZERO],
                triangles: vec![[0, 0, 3]],
            })
            .unwrap_err()
        );
    }

    #[test]
    fn nonmanifold_book() {
        // Spine (0,1) shared by 4 pages.
        let mut positions = vec![Vec3::ZERO, Vec3::Z];
        let mut triangles = Vec::new();
        for k in 0..4 {
            let ang = k as f32;
            positions.push(Vec3::new(ang.cos(), ang.sin(), 0.5));
            triangles.push([0, 1, 2 + k]);
        }
        let t = EdgeTable::build(&Mesh::new(positions, triangles).unwrap()).unwrap();
        assert_eq!(t.stats.nonmanifold_edges, 1);
        assert_eq!(t.stats.boundary_edges, 8);
        assert!(t.ovs_of(0).eq([2, 3, 4, 5]));
        assert_eq!(t.manifold_neighbors()[0][0], NO_NEIGHBOR);
    }

    #[test]
    fn degenerate_after_weld_dropped() {
        let p = vec![Vec3::ZERO, Vec3::X, Vec3::X, Vec3::Y];
        let t = EdgeTable::build(&Mesh::new(p, vec![[0, 1, 2], [0, 1, 3]]).unwrap()).unwrap();
        assert_eq!(t.stats.degenerate_triangles, 1);
        assert_eq!(t.triangles.len(), 1);
        assert_eq!(t.triangle_sources, Renumbering::Stored(vec![1]));
        // A mesh with nothing to weld or drop stores neither map.
        let closed = EdgeTable::build(
            &Mesh::new(
                vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z],
                vec![[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]],
            )
            .unwrap(),
        )
        .unwrap();
        assert!(closed.triangle_sources.is_identity() && closed.vertex_names.is_identity());
        assert_eq!(closed.edge_index(3, 1), Some(4));
        assert_eq!(closed.tri_edges()[0], [1, 3, 0]);
    }

    #[test]
    fn errors_name_the_place() {
        let e = Mesh::new(vec![Vec3::ZERO], vec![[0, 0, 7]]).unwrap_err();
        assert_eq!(
            e,
            MeshError::IndexOutOfRange {
                triangle: 0,
                corner: 2,
                index: 7,
                vertices: 1
            }
        );
        let e = Mesh::new(vec![Vec3::new(0.0, f32::NAN, 0.0)], vec![]).unwrap_err();
        assert!(e.to_string().contains("vertex 0: coordinate y"));
    }
}

/// The README's examples, compiled and run as doctests.
#[doc = include_str!("../README.md")]
#[cfg(doctest)]
pub struct ReadmeDoctests;
