//! `tables.md`'s "Volumes against maps": per scene the volumes and each map size and filter,
//! with Bevy's bias and with the best bias of the sweep ("tuned with hindsight"), then a summary
//! per scene; and the points of `maps_vs_volumes.png`.

use super::args::MODES;
use super::plan::{FRAME_GPU_KEY, FRAME_HOST_BACKEND, MAP_KEY};
use super::records::{Record, Render, Results};
use super::tables::fmt_ms;

/// One row of the table: a technique on one scene.
#[derive(Debug, Clone)]
pub(crate) struct Row<'a> {
    /// What drew the shadows, in words (`volumes gpu exact`, `map 2048 pcf`).
    pub label: String,
    /// `volumes`, `map` or `map tuned`.
    pub kind: &'static str,
    /// The timed render (for a tuned row: the default-bias render of the same size and filter,
    /// whose frame time it shares: the bias changes no work).
    pub timed: &'a Render,
    /// The render whose pixels the row reports.
    pub pixels: &'a Render,
}

/// The rows of `scene`: volumes (GPU pipeline per mode, host exact), then per map size and
/// filter the default bias and the tuned one.
pub(crate) fn rows<'a>(records: &'a [Record], scene: &str) -> Vec<Row<'a>> {
    let of = |exp: &'static str| {
        records
            .iter()
            .filter(move |x| x.experiment == exp && x.key.scene == scene)
            .filter_map(|x| Some((x, x.render()?)))
    };
    let mut rows = Vec::new();
    for m in MODES {
        if let Some((_, x)) = of("maps").find(|(x, _)| x.is("maps", None, FRAME_GPU_KEY, m)) {
            rows.push(volume_row(format!("volumes, GPU pipeline, {m}"), x));
        }
    }
    if let Some((_, x)) = of("maps").find(|(x, _)| x.is("maps", None, FRAME_HOST_BACKEND, "exact"))
    {
        rows.push(volume_row(
            format!("volumes, host pipeline ({FRAME_HOST_BACKEND}), exact"),
            x,
        ));
    }
    let mut maps: Vec<(u64, String)> = of("maps")
        .filter(|(x, _)| x.key.backend == MAP_KEY)
        .filter_map(|(_, x)| Some((x.map_size?, x.map_filter.clone()?)))
        .collect();
    maps.sort();
    maps.dedup();
    for (size, filter) in maps {
        let same =
            |x: &Render| x.map_size == Some(size) && x.map_filter.as_deref() == Some(&filter);
        let Some((_, default)) = of("maps").find(|(x, y)| x.key.backend == MAP_KEY && same(y))
        else {
            continue;
        };
        rows.push(Row {
            label: format!("map {size} {filter}, Bevy's bias"),
            kind: "map",
            timed: default,
            pixels: default,
        });
        let best = std::iter::once(default)
            .chain(of("maps-sweep").map(|(_, y)| y).filter(|y| same(y)))
            .min_by_key(|y| {
                (
                    y.artifact_pixels.unwrap_or(u64::MAX),
                    y.boundary_pixels.unwrap_or(u64::MAX),
                )
            })
            .expect("the default is one");
        rows.push(Row {
            label: format!(
                "map {size} {filter}, tuned with hindsight (bias {})",
                best.map_bias.as_deref().unwrap_or("default")
            ),
            kind: "map tuned",
            timed: default,
            pixels: best,
        });
    }
    rows
}

fn volume_row(label: String, x: &Render) -> Row<'_> {
    Row {
        label,
        kind: "volumes",
        timed: x,
        pixels: x,
    }
}

/// The scenes of the table, in the order they ran.
pub(crate) fn scenes(records: &[Record]) -> Vec<&str> {
    let mut out: Vec<&str> = Vec::new();
    for x in records.iter().filter(|x| x.experiment == "maps") {
        if !out.contains(&x.key.scene.as_str()) {
            out.push(&x.key.scene);
        }
    }
    out
}

fn count(v: Option<u64>) -> String {
    v.map_or("n/a".to_owned(), |n| n.to_string())
}

fn frames(x: &Render) -> String {
    format!(
        "{} ({}-{})",
        fmt_ms(x.frames_median_ms),
        fmt_ms(x.frames_p10_ms),
        fmt_ms(x.frames_p90_ms)
    )
}

/// `tables.md`'s section; empty without any `maps` record.
pub(super) fn maps_tables(r: &Results) -> String {
    let records = &r.records;
    let scenes = scenes(records);
    if scenes.is_empty() {
        return String::new();
    }
    let size = records
        .iter()
        .find(|x| x.experiment == "maps")
        .and_then(Record::render)
        .map_or("?", |x| x.size.as_str());
    let mut s = format!(
        "\n## Volumes against maps\n\n`render SCENE --reference --frames N` at {size}: the \
         volumes (GPU pipeline in each mode, host pipeline in exact mode) and shadow maps \
         (`--shadows map --map-size S --map-filter F`) with Bevy 0.20's bias and with the bias \
         of the sweep that leaves the fewest artifact pixels (\"tuned with hindsight\": its frame \
         time is the default bias's, the bias changes no work). Frame time: median (p10-p90) \
         ms of the frames on the light orbit; `/ exact` is the frame time over that of exact \
         volumes on the GPU pipeline. Artifact pixels differ from the reference more than one \
         pixel from its shadow boundaries; boundary pixels differ within one pixel.\n\n"
    );
    s += &summary(records, &scenes);
    s += "\n| scene | shadows | frame ms | / exact | artifact px | boundary px | shadow px (reference) |\n|---|---|---|---|---|---|---|\n";
    for sc in &scenes {
        let rows = rows(records, sc);
        let exact = exact_ms(&rows);
        for row in &rows {
            let ratio = match (row.timed.frames_median_ms, exact) {
                (Some(a), Some(e)) if e > 0.0 => format!("{:.2}", a / e),
                _ => "n/a".to_owned(),
            };
            s += &format!(
                "| {sc} | {} | {} | {ratio} | {} | {} | {} ({}) |\n",
                row.label,
                frames(row.timed),
                count(row.pixels.artifact_pixels),
                count(row.pixels.boundary_pixels),
                count(row.pixels.shadow_pixels),
                count(row.pixels.reference_shadow_pixels),
            );
        }
    }
    s += "\n![maps against volumes](maps_vs_volumes.png)\n";
    s
}

/// The frame time of exact volumes on the GPU pipeline among `rows`.
fn exact_ms(rows: &[Row<'_>]) -> Option<f64> {
    rows.iter()
        .find(|x| x.label == "volumes, GPU pipeline, exact")
        .and_then(|x| x.timed.frames_median_ms)
}

/// Per scene: exact volumes, Bevy's default map, the first map (by size, tuned) that leaves no
/// more artifacts than exact volumes, and the fewest artifacts any map left.
fn summary(records: &[Record], scenes: &[&str]) -> String {
    let mut s = "| scene | exact volumes: ms, artifact px | first map as good as exact volumes | its ms | exact / map | fewest artifact px of any map |\n|---|---|---|---|---|---|\n".to_owned();
    for sc in scenes {
        let rows = rows(records, sc);
        let exact = rows
            .iter()
            .find(|x| x.label == "volumes, GPU pipeline, exact");
        let target = exact.and_then(|x| x.pixels.artifact_pixels).unwrap_or(0);
        let maps: Vec<&Row<'_>> = rows.iter().filter(|x| x.kind != "volumes").collect();
        let first = maps
            .iter()
            .filter(|x| x.pixels.artifact_pixels.is_some_and(|a| a <= target))
            .min_by(|a, b| {
                (
                    a.timed.map_size,
                    a.timed.frames_median_ms.unwrap_or(f64::MAX),
                )
                    .partial_cmp(&(
                        b.timed.map_size,
                        b.timed.frames_median_ms.unwrap_or(f64::MAX),
                    ))
                    .unwrap_or(std::cmp::Ordering::Equal)
            });
        let fewest = maps.iter().filter_map(|x| x.pixels.artifact_pixels).min();
        let exact_ms = exact.and_then(|x| x.timed.frames_median_ms);
        let (label, ms, ratio) = match first {
            Some(m) => (
                m.label.clone(),
                fmt_ms(m.timed.frames_median_ms),
                match (exact_ms, m.timed.frames_median_ms) {
                    (Some(e), Some(t)) if t > 0.0 => format!("{:.2}", e / t),
                    _ => "n/a".to_owned(),
                },
            ),
            None => ("none".to_owned(), "n/a".to_owned(), "n/a".to_owned()),
        };
        s += &format!(
            "| {sc} | {}, {} | {label} | {ms} | {ratio} | {} |\n",
            fmt_ms(exact_ms),
            count(exact.and_then(|x| x.pixels.artifact_pixels)),
            count(fewest),
        );
    }
    s
}

/// The points of `maps_vs_volumes.png`: per technique (the row label without the scene), the
/// summed median frame time and the artifact share over the scenes where every technique ran.
pub(crate) fn plot_points(records: &[Record]) -> Vec<(String, &'static str, f64, f64)> {
    let scenes = scenes(records);
    let per_scene: Vec<Vec<Row<'_>>> = scenes.iter().map(|sc| rows(records, sc)).collect();
    let Some(first) = per_scene.first() else {
        return Vec::new();
    };
    let labels: Vec<(String, &'static str)> =
        first.iter().map(|x| (generic(&x.label), x.kind)).collect();
    let mut out = Vec::new();
    for (label, kind) in labels {
        let mut ms = 0.0;
        let mut artifacts = 0u64;
        let mut pixels = 0u64;
        let mut complete = true;
        for rows in &per_scene {
            let Some(row) = rows.iter().find(|x| generic(&x.label) == label) else {
                complete = false;
                break;
            };
            let (Some(t), Some(a)) = (row.timed.frames_median_ms, row.pixels.artifact_pixels)
            else {
                complete = false;
                break;
            };
            ms += t;
            artifacts += a;
            pixels += image_pixels(&row.pixels.size);
        }
        if complete && pixels > 0 {
            out.push((label, kind, ms, artifacts as f64 / pixels as f64));
        }
    }
    out
}

/// A row's label without the tuned bias (which differs per scene).
fn generic(label: &str) -> String {
    label.split(" (bias").next().unwrap_or(label).to_owned()
}

fn image_pixels(size: &str) -> u64 {
    size.split_once('x')
        .and_then(|(w, h)| Some(w.parse::<u64>().ok()? * h.parse::<u64>().ok()?))
        .unwrap_or(0)
}
