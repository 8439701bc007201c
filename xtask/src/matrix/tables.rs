//! `tables.md`: the paper's tables redone on this machine, next to the paper's figures.

use super::plan::{
    FRAME_GPU_KEY, FRAME_HOST_BACKEND, LIGHT_SCENE, T1_SCENE, T2_SCENES, T3_SCENES, TRI_SCENES,
};
use super::records::{ModeErrors, Record, Render, Results};
use std::collections::BTreeSet;

/// Table 1 of the paper: FPS robust / original, 2013 hardware (GPU columns: GF650Ti, AMD7950,
/// HD3000, HD4000), ~10^5-10^6 triangles.
const PAPER_T1: &str = "\
| platform | GF650Ti | AMD7950 | HD3000 | HD4000 |
|---|---|---|---|---|
| CPU | 4.9 / 5.0 | 12.9 / 13.9 | 9.9 / 11.2 | 6.3 / 5.9 |
| AVX+OMP | 4.9 / 5.1 | 11.8 / 13.5 | 10.0 / 12.4 | 6.6 / 8.6 |
| GS | 30 / 40 | 92 / 98 | n/a | 4.4 / 8.7 |
| OpenCL | 42 / 41 | 83 / 80 | n/a | 7.6 / 7.7 |
";

/// Table 2 of the paper (FPS, robust): individual bunnies / baked bunnies / individual spheres /
/// baked spheres, ~6.5*10^5 triangles.
const PAPER_T2: &str = "\
| platform | scene | GF650Ti | AMD7950 | HD3000 | HD4000 |
|---|---|---|---|---|---|
| CPU | bunnies ind. / baked | 4.9 / 5.0 | 12.9 / 7.8 | 9.9 / 11.0 | 6.3 / 5.4 |
| CPU | spheres ind. / baked | 5.5 / 5.5 | 13.3 / 9.6 | 12.2 / 10 | 9.6 / 5.5 |
| AVX+OMP | bunnies ind. / baked | 4.9 / 5.1 | 12.9 / 4.3 | 9.9 / 6.2 | 6.3 / 6.0 |
| AVX+OMP | spheres ind. / baked | 5.5 / 5.5 | 12.8 / 5.2 | 12.8 / 5.1 | 11.9 / 6.2 |
| GS | bunnies ind. / baked | 30 / 30 | 92 / 95 | n/a | 4.4 / n/a |
| GS | spheres ind. / baked | 34 / 34 | 156 / 124 | n/a | 6.0 / n/a |
| OpenCL | bunnies ind. / baked | 42 / 52 | 83 / 96 | n/a | 8.1 / 8.2 |
| OpenCL | spheres ind. / baked | 54 / 67 | 142 / 147 | n/a | 11.3 / 6.0 |
";

/// Table 3 of the paper (FPS): sphere 10^6 / sphere 10^5 / 100 spheres of 10^4 / 100 of 10^3.
const PAPER_T3: &str = "\
| platform | scene | GF650Ti | AMD7950 | HD3000 | HD4000 |
|---|---|---|---|---|---|
| CPU | sphere 1M / 100k | 3.9 / 35 | 5.1 / 81 | 5.3 / 34 | 37 / 20 |
| CPU | 100x10k / 100x1k | 3.4 / 27 | 8.4 / 61 | 6.5 / 32 | 4.4 / 18.5 |
| AVX+OMP | sphere 1M / 100k | 3.9 / 35 | 5.7 / 81 | 4.9 / 32 | 4.2 / 23 |
| AVX+OMP | 100x10k / 100x1k | 3.4 / 28 | 9.3 / 63 | 6.7 / 34 | 5.0 / 24 |
| GS | sphere 1M / 100k | 23 / 165 | 85 / 650 | n/a | 3.7 / 15 |
| GS | 100x10k / 100x1k | 18.7 / 100 | 84 / 482 | n/a | 3.1 / 19.3 |
| OpenCL | sphere 1M / 100k | 43 / 192 | 91 / 430 | n/a | 6.0 / 19.3 |
| OpenCL | 100x10k / 100x1k | 13.4 / 26 | 22 / 54 | n/a | 4.4 / 9.1 |
";

/// Toy Wars notes: silhouette times (ms) of the seed's algorithms (PSP-era hardware).
const PAPER_TOYWARS: &str = "\
| model | classic | fast (64) | fast (8) | connectivity |
|---|---|---|---|---|
| Dino | 9000 | 160 | 49 | 31 |
| Dragon | 2100 | 270 | 44 | 13 |
";

/// The whole of `tables.md` for `r`, with `modes` as the mode columns and rows.
pub(super) fn tables(r: &Results, modes: &[String]) -> String {
    let t = Tables { r, modes };
    let mut s = t.header();
    // `--only maps`: the other tables would only say they have no data.
    if !r.records.is_empty() && r.records.iter().all(|x| x.experiment.starts_with("maps")) {
        return s + &super::maps_table::maps_tables(r) + &t.failures();
    }
    // `--only memory`.
    if !r.records.is_empty() && r.records.iter().all(|x| x.experiment == "memory") {
        return s + &super::memory_table::memory_tables(r) + &t.failures();
    }
    // `--only soft`.
    if !r.records.is_empty() && r.records.iter().all(|x| x.experiment == "soft") {
        return s + &super::soft_table::soft_tables(&r.records) + &t.failures();
    }
    s += &t.table1();
    s += "\n## Table 2: individual vs baked objects (~6.5*10^5 triangles)\n\n";
    s += &t.scene_table("table2", &T2_SCENES);
    s += "\nThe paper (2013 hardware, FPS, robust):\n\n";
    s += PAPER_T2;
    s += "\n## Table 3: number of triangles and of objects\n\n";
    s += &t.scene_table("table3", &T3_SCENES);
    s += "\nThe paper (2013 hardware, FPS, robust):\n\n";
    s += PAPER_T3;
    s += &t.accuracy_table();
    s += &t.artifact_table();
    s += &t.scaling_tables();
    s += &t.frame_table();
    s += &super::maps_table::maps_tables(r);
    s += &super::memory_table::memory_tables(r);
    s += &super::soft_table::soft_tables(&r.records);
    s += "\n## Seed \"Toy Wars\" table: the seeds' CPU algorithms against ours\n\n";
    s += &t.toywars_table();
    s += "\nThe Toy Wars notes (PSP-era hardware, ms):\n\n";
    s += PAPER_TOYWARS;
    s += "\n## Plots\n\n![time vs triangles](time_vs_triangles.png)\n![time vs lights](time_vs_lights.png)\n![accuracy cost](accuracy_cost.png)\n![individual vs baked](individual_vs_baked.png)\n";
    s + &t.failures()
}

/// Milliseconds with three significant digits or so; `n/a` for none.
pub(super) fn fmt_ms(v: Option<f64>) -> String {
    match v {
        Some(x) if x >= 100.0 => format!("{x:.0}"),
        Some(x) if x >= 10.0 => format!("{x:.1}"),
        Some(x) => format!("{x:.2}"),
        None => "n/a".into(),
    }
}

/// `| a | b |` and its `|---|---|` line for a table with `lead` first columns (already
/// written as `| x | y |`) and one column per item of `cols`.
fn header_row<T: std::fmt::Display>(lead: &str, cols: impl IntoIterator<Item = T>) -> String {
    let mut s = lead.to_owned();
    let mut rule = "\n|".to_owned() + &"---|".repeat(lead.matches('|').count() - 1);
    for c in cols {
        s += &format!(" {c} |");
        rule += "---|";
    }
    s + &rule + "\n"
}

struct Tables<'a> {
    r: &'a Results,
    modes: &'a [String],
}

impl<'a> Tables<'a> {
    /// The failures and the measurements left out on purpose, empty without either.
    fn failures(&self) -> String {
        let mut s = String::new();
        if !self.r.failures.is_empty() {
            s += "\n## Failures\n\n";
            for f in &self.r.failures {
                s += &format!("- {}\n", f.replace('\n', " "));
            }
        }
        if !self.r.skips.is_empty() {
            s += "\n## Left out\n\n";
            for f in &self.r.skips {
                s += &format!("- {}\n", f.replace('\n', " "));
            }
        }
        s
    }

    /// The records of `experiment` with their measurement `data` (those that have one).
    fn records<T>(
        &self,
        experiment: &str,
        data: fn(&'a Record) -> Option<&'a T>,
    ) -> Vec<(&'a Record, &'a T)> {
        self.r
            .records
            .iter()
            .filter(|r| r.experiment == experiment)
            .filter_map(|r| Some((r, data(r)?)))
            .collect()
    }

    fn header(&self) -> String {
        let r = self.r;
        let h = &r.host;
        let get = |v: &Option<String>| v.clone().unwrap_or_else(|| "?".into());
        let mut s = String::from("# shadowvol experiment matrix\n\n");
        s += &format!(
            "Command: `{}` ({} warm-up and {} timed frames per measurement; {:.0} s in \
             all).\n\n",
            r.command,
            r.warmup(),
            r.frames,
            r.elapsed_s
        );
        s += "**This machine**: ";
        s += &format!(
            "{} ({} cores), {}, {}, git {}, RUSTFLAGS=`{}`.\n\n",
            get(&h.cpu),
            h.cores.map_or("?".into(), |n| n.to_string()),
            get(&h.os),
            get(&h.rustc),
            get(&h.git_rev),
            get(&h.rustflags)
        );
        s += "| backend | device |\n|---|---|\n";
        for b in &r.backends {
            s += &format!(
                "| {b} | {} |\n",
                r.devices.get(b).map_or("", String::as_str)
            );
        }
        for u in &r.unavailable {
            s += &format!("| {} | unavailable: {} |\n", u.name, u.reason);
        }
        s += &format!(
            "\nSIMD level used by `simd`: {}. Build: {}.\n",
            get(&h.simd_level),
            get(&h.flags)
        );
        s +=
            "\nTimes are medians over the timed frames after warm-up, in milliseconds (p10-p90 in \
              results.json). `floor` is the time to stream the bytes the extraction must touch, \
              measured in the same run. Absolute times of GPU backends only mean something on a \
              real GPU; on lavapipe/PoCL they run on this CPU.\n\n";
        s
    }

    fn table1(&self) -> String {
        let r = self.r;
        let mut s =
            format!("## Table 1: accuracy modes on `{T1_SCENE}` (silhouette and full frame)\n\n");
        s += "Ours (this machine): silhouette ms (median of `bench`) / frame ms (one `render` frame at the run's image size: silhouettes, side building and raster, without the one-off upload of the edge tables), and the silhouette time's ratio to `original`.\n\n";
        s += &header_row(
            "| backend |",
            self.modes.iter().chain([&"floor".to_owned()]),
        );
        for b in &r.backends {
            s += &format!("| {b} |");
            let orig = r.ms("table1", T1_SCENE, b, "original");
            for m in self.modes {
                let sil = r.ms("table1", T1_SCENE, b, m);
                let frame = r
                    .records
                    .iter()
                    .filter(|x| x.is("table1-frame", Some(T1_SCENE), b, m))
                    .find_map(Record::render)
                    .and_then(|x| x.frame_ms);
                let ratio = match (sil, orig) {
                    (Some(x), Some(o)) if o > 0.0 => format!(" ({:.2}x)", x / o),
                    _ => String::new(),
                };
                s += &format!(" {} / {}{} |", fmt_ms(sil), fmt_ms(frame), ratio);
            }
            let floor = r
                .bench("table1", T1_SCENE, b, "original", Some(1))
                .and_then(|x| x.floor_ms);
            s += &format!(" {} |\n", fmt_ms(floor));
        }
        s += "\nThe paper (2013 hardware, FPS of the whole frame, robust / original):\n\n";
        s + PAPER_T1
    }

    /// One row per backend and mode (`robust`, `original`), one column per scene: silhouette
    /// ms of `experiment`.
    fn scene_table(&self, experiment: &str, scenes: &[&str]) -> String {
        let mut s = String::from("Ours (this machine), silhouette ms:\n\n");
        s += &header_row("| backend | mode |", scenes);
        for b in &self.r.backends {
            for m in ["robust", "original"] {
                if !self.modes.iter().any(|x| x == m) {
                    continue;
                }
                s += &format!("| {b} | {m} |");
                for sc in scenes {
                    s += &format!(" {} |", fmt_ms(self.r.ms(experiment, sc, b, m)));
                }
                s += "\n";
            }
        }
        s
    }

    fn accuracy_table(&self) -> String {
        let r = self.r;
        let mut s = "\n## What accuracy costs\n\n".to_owned();
        s += &format!(
            "Time relative to `original` on `{T1_SCENE}`; open vertices (vertices where the \
             silhouette chain does not close) and edges whose sign differs from `exact`, summed \
             over every hard-* scene and light; artifact pixels against the ray-traced reference, \
             summed over the rendered hard scenes.\n\n"
        );
        s += "| backend | mode | time / original | open vertices | sign differs from exact | artifact pixels | uncertain (host-decided) |\n|---|---|---|---|---|---|---|\n";
        for b in &r.backends {
            let orig = r.ms("table1", T1_SCENE, b, "original");
            for m in self.modes {
                let ratio = match (r.ms("table1", T1_SCENE, b, m), orig) {
                    (Some(x), Some(o)) if o > 0.0 => format!("{:.2}", x / o),
                    _ => "n/a".into(),
                };
                let acc: Vec<&ModeErrors> = r
                    .records
                    .iter()
                    .filter(|x| x.is("accuracy", None, b, m))
                    .filter_map(Record::mode_errors)
                    .collect();
                let acc_sum = |f: fn(&ModeErrors) -> Option<u64>| {
                    total(acc.iter().map(|a| f(a).unwrap_or(0)))
                };
                let art = total(
                    r.records
                        .iter()
                        .filter(|x| x.is("artifacts", None, b, m))
                        .filter_map(|x| x.render()?.artifact_pixels),
                );
                s += &format!(
                    "| {b} | {m} | {ratio} | {} | {} | {art} | {} |\n",
                    acc_sum(|a| a.open_vertices),
                    acc_sum(|a| a.sign_diff_vs_exact),
                    acc_sum(|a| a.uncertain)
                );
            }
        }
        s
    }

    /// Artifact pixels per rendered scene (rows) and mode (columns): one number when every
    /// backend got the same count, else the count of each backend in table order.
    /// The frame table: host pipeline (`simd`) against GPU pipeline, `--frames` on the light
    /// orbit, exact mode; empty when the run has no such records.
    fn frame_table(&self) -> String {
        let recs = self.records("frames", Record::render);
        if recs.is_empty() {
            return String::new();
        }
        let scenes = scenes_of(&recs);
        let size = recs.first().map_or("?", |(_, x)| x.size.as_str());
        let mut s = format!(
            "\n## Frames: host pipeline against GPU pipeline\n\n`render SCENE --frames N --mode \
             exact` at {size}, the lights turning 1 degree per frame (every frame re-extracts), \
             both pipelines back to back: median ms (p10-p90), the GPU pipeline's time as a \
             ratio of the host's, and the bytes read back during the frames.\n\n"
        );
        s += &format!(
            "| scene | host ({FRAME_HOST_BACKEND}) ms | GPU pipeline ms | gpu / host | read back host / gpu |\n|---|---|---|---|---|\n"
        );
        let cell = |x: Option<&Render>| {
            x.map_or("n/a".to_owned(), |x| {
                format!(
                    "{} ({}-{})",
                    fmt_ms(x.frames_median_ms),
                    fmt_ms(x.frames_p10_ms),
                    fmt_ms(x.frames_p90_ms)
                )
            })
        };
        for sc in scenes {
            let find = |key: &str| {
                recs.iter()
                    .find(|(r, _)| r.key.scene == sc && r.key.backend == key)
                    .map(|(_, x)| *x)
            };
            let (h, g) = (find(FRAME_HOST_BACKEND), find(FRAME_GPU_KEY));
            let ratio = match (
                h.and_then(|x| x.frames_median_ms),
                g.and_then(|x| x.frames_median_ms),
            ) {
                (Some(a), Some(b)) if a > 0.0 => format!("{:.2}x", b / a),
                _ => "n/a".to_owned(),
            };
            let bytes = |x: Option<&Render>| {
                x.and_then(|x| x.frame_readback_bytes)
                    .map_or("n/a".to_owned(), |n| n.to_string())
            };
            s += &format!(
                "| {sc} | {} | {} | {ratio} | {} / {} |\n",
                cell(h),
                cell(g),
                bytes(h),
                bytes(g)
            );
        }
        s
    }

    fn artifact_table(&self) -> String {
        let available = &self.r.backends;
        let recs = self.records("artifacts", Record::render);
        let scenes = scenes_of(&recs);
        let size = recs.first().map_or("?", |(_, x)| x.size.as_str());
        let mut s = format!(
            "\nArtifact pixels per rendered scene ({size} pixels, `--backdrop` behind the hard-* \
             scenes). One number when all backends \
             agree, else one per backend ({}):\n\n",
            available.join(" / ")
        );
        s += &header_row("| scene | reference shadow pixels |", self.modes);
        for sc in scenes {
            let shadow = recs
                .iter()
                .find(|(r, _)| r.key.scene == sc && r.mode() == Some("exact"))
                .or_else(|| recs.iter().find(|(r, _)| r.key.scene == sc))
                .and_then(|(_, x)| x.reference_shadow_pixels.or(x.shadow_pixels))
                .map_or("?".to_owned(), |n| n.to_string());
            s += &format!("| {sc} | {shadow} |");
            for m in self.modes {
                let per: Vec<String> = available
                    .iter()
                    .map(|b| {
                        recs.iter()
                            .find(|(r, _)| r.is("artifacts", Some(sc), b, m))
                            .and_then(|(_, x)| x.artifact_pixels)
                            .map_or("n/a".to_owned(), |n| n.to_string())
                    })
                    .collect();
                let cell = if per.windows(2).all(|w| w[0] == w[1]) {
                    per.first().cloned().unwrap_or_default()
                } else {
                    per.join(" / ")
                };
                let cell = if cell != "0" && cell != "n/a" {
                    format!("**{cell}**")
                } else {
                    cell
                };
                s += &format!(" {cell} |");
            }
            s += "\n";
        }
        s
    }

    /// The thesis' scaling: time against lights, and against triangles.
    fn scaling_tables(&self) -> String {
        let r = self.r;
        let mut s =
            format!("\n## Scaling (the thesis): time against lights on `{LIGHT_SCENE}`\n\n");
        let counts: BTreeSet<u64> = r
            .records
            .iter()
            .filter(|x| x.experiment == "lights")
            .filter_map(|x| x.bench()?.lights)
            .collect();
        s += &header_row("| backend | mode |", &counts);
        for b in &r.backends {
            for m in self.modes {
                s += &format!("| {b} | {m} |");
                for &n in &counts {
                    let v = r
                        .bench("lights", LIGHT_SCENE, b, m, Some(n))
                        .and_then(|x| x.median_ms);
                    s += &format!(" {} |", fmt_ms(v));
                }
                s += "\n";
            }
        }
        s += "\n## Scaling (the thesis): time against triangles (one light)\n\n";
        s += &header_row("| backend | mode |", TRI_SCENES);
        for b in &r.backends {
            for m in self.modes {
                s += &format!("| {b} | {m} |");
                for sc in TRI_SCENES {
                    s += &format!(" {} |", fmt_ms(r.ms("triangles", sc, b, m)));
                }
                s += "\n";
            }
        }
        s
    }

    /// One row per algorithm (the seeds' and ours per backend and mode), one column group per
    /// scene: median ms (p10-p90), silhouette edges, and whether the edge set equals exact's.
    fn toywars_table(&self) -> String {
        let recs = self.records("toywars", Record::baseline);
        if recs.is_empty() {
            return "No data in this run (see Failures).\n".into();
        }
        let mut scenes: Vec<(&str, u64)> = Vec::new();
        let mut rows: Vec<(&str, &str)> = Vec::new();
        for (r, x) in &recs {
            if !scenes.iter().any(|(sc, _)| *sc == r.key.scene) {
                scenes.push((&r.key.scene, x.triangles.unwrap_or(0)));
            }
            let row = (r.key.backend.as_str(), r.mode().unwrap_or("-"));
            if !rows.contains(&row) {
                rows.push(row);
            }
        }
        let mut s = String::from("| algorithm | mode |");
        for (sc, t) in &scenes {
            s += &format!(" {sc} ({t} tri.) ms | silhouette edges | = exact |");
        }
        s += "\n|---|---|";
        s += &"---|---|---|".repeat(scenes.len());
        s += "\n";
        for (alg, mode) in &rows {
            s += &format!("| {alg} | {mode} |");
            for (sc, _) in &scenes {
                let found = recs.iter().find(|(r, _)| {
                    r.key.scene == *sc && r.key.backend == *alg && r.mode().unwrap_or("-") == *mode
                });
                match found {
                    Some((_, x)) if x.median_ms.is_some() => {
                        s += &format!(
                            " {} ({}-{}) | {} | {} |",
                            fmt_ms(x.median_ms),
                            fmt_ms(x.p10_ms),
                            fmt_ms(x.p90_ms),
                            x.silhouette_edges.map_or("null".into(), |n| n.to_string()),
                            match x.agrees_with_exact {
                                Some(true) => "yes",
                                Some(false) => "**no**",
                                None => "?",
                            }
                        );
                    }
                    Some((_, x)) => {
                        s += &format!(
                            " failed: {} | | |",
                            x.error.as_deref().unwrap_or("?").replace('|', "/")
                        );
                    }
                    None => s += " n/a | | |",
                }
            }
            s += "\n";
        }
        s += "\nThe seeds' algorithms (`classic`, `fast-hash-N`, `connectivity`, `two-step`) are \
              single-threaded scalar code with an f32 facing test per triangle; `= exact` compares \
              the edge set (m != 0, every light) with the `cpu` backend's `exact` result.\n";
        s
    }
}

/// The sum of `values`, `n/a` when there are none.
fn total(values: impl Iterator<Item = u64>) -> String {
    let v: Vec<u64> = values.collect();
    if v.is_empty() {
        "n/a".to_owned()
    } else {
        v.iter().sum::<u64>().to_string()
    }
}

/// The scenes of `recs`, each once, in the order they first appear.
fn scenes_of<'a, T>(recs: &[(&'a Record, &T)]) -> Vec<&'a str> {
    let mut scenes: Vec<&str> = Vec::new();
    for (r, _) in recs {
        if !scenes.contains(&r.key.scene.as_str()) {
            scenes.push(&r.key.scene);
        }
    }
    scenes
}
