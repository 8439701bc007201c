//! The memory table of `tables.md` and the points of its plot, from the `memory` records.

use super::records::{Record, Results};
use std::collections::BTreeMap;
use std::fmt::Write as _;

/// One series per backend or pipeline: (triangles, peak RSS bytes per triangle).
pub(crate) fn plot_points(records: &[Record]) -> BTreeMap<String, Vec<(f64, f64)>> {
    let mut s: BTreeMap<String, Vec<(f64, f64)>> = BTreeMap::new();
    for r in records.iter().filter(|r| r.experiment == "memory") {
        let Some(m) = r.memory().filter(|m| m.build_ms.is_none()) else {
            continue;
        };
        if let (Some(t), Some(b)) = (m.triangles, m.per_triangle(m.peak_rss_bytes)) {
            s.entry(r.key.backend.clone())
                .or_default()
                .push((t as f64, b));
        }
    }
    for v in s.values_mut() {
        v.sort_by(|a, b| a.0.total_cmp(&b.0));
    }
    s
}

/// `## Memory per triangle`: per scene, each backend (`silhouette`) and pipeline (`render`)
/// with its peak RSS and what the prepared scene held, in bytes per triangle.
pub(crate) fn memory_tables(r: &Results) -> String {
    let recs: Vec<&Record> = r
        .records
        .iter()
        .filter(|x| x.experiment == "memory")
        .collect();
    if recs.is_empty() {
        return String::new();
    }
    let mut s = String::from(
        "\n## Memory per triangle\n\n\
         Each row is one process: `shadowvol silhouette SCENE --backend B --mode exact` or \
         `shadowvol render SCENE` on a pipeline (1280x720). Peak is the process's peak resident \
         set (the kernel's VmHWM; on lavapipe and PoCL device memory is host memory, so it \
         counts); table is what the prepared scene held: its edge tables (topology), the \
         backend's or pipeline's host layout, and its device buffers. Bytes per triangle of the \
         scene.\n\n\
         | scene | triangles | run | peak B/tri | table B/tri | topology | host | device | peak MB | wall s |\n\
         |---|---|---|---|---|---|---|---|---|---|\n",
    );
    let f = |x: Option<f64>| x.map_or_else(|| "-".to_owned(), |v| format!("{v:.0}"));
    for x in &recs {
        let Some(m) = x.memory().filter(|m| m.build_ms.is_none()) else {
            continue;
        };
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |",
            x.key.scene,
            m.triangles
                .map_or_else(|| "-".to_owned(), |t| t.to_string()),
            x.key.backend,
            f(m.per_triangle(m.peak_rss_bytes)),
            f(m.per_triangle(m.table_bytes)),
            f(m.per_triangle(m.topology_bytes)),
            f(m.per_triangle(m.host_bytes)),
            f(m.per_triangle(m.device_bytes)),
            f(m.peak_rss_bytes.map(|b| b as f64 / 1e6)),
            m.wall_s
                .map_or_else(|| "-".to_owned(), |w| format!("{w:.1}")),
        );
    }
    s += "\n![bytes per triangle](memory_per_triangle.png)\n";
    s + &build_table(&recs)
}

/// `### Edge-table build`: `EdgeTable::build` against reading its input, from the `build`
/// records; empty without them.
fn build_table(recs: &[&Record]) -> String {
    let rows: Vec<String> = recs
        .iter()
        .filter_map(|x| {
            let m = x.memory()?;
            let (build, read) = (m.build_ms?, m.build_read_ms?);
            Some(format!(
                "| {} | {} | {:.0} | {:.2} | {:.0} | {} |",
                x.key.scene,
                m.triangles
                    .map_or_else(|| "-".to_owned(), |t| t.to_string()),
                build,
                read,
                build / read.max(1e-9),
                m.build_threads
                    .map_or_else(|| "-".to_owned(), |t| t.to_string()),
            ))
        })
        .collect();
    if rows.is_empty() {
        return String::new();
    }
    let mut s = String::from(
        "\n### Edge-table build\n\n\
         `EdgeTable::build` (weld, counting sort, grouping) of the scene's mesh, median of \
         several builds, against reading the mesh's bytes (12 per vertex and per triangle) \
         from memory on the same threads (`shadowvol bench --build-runs`).\n\n\
         | scene | triangles | build ms | read ms | build / read | threads |\n\
         |---|---|---|---|---|---|\n",
    );
    for r in rows {
        let _ = writeln!(s, "{r}");
    }
    s
}
