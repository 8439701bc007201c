//! PNG plots of the matrix records, drawn with plotters and a bundled font (DejaVu Sans, see
//! assets/fonts), so no system font library is needed.

use crate::matrix::records::Record;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::collections::BTreeMap;
use std::path::Path;

static FONT: &[u8] = include_bytes!("../../assets/fonts/DejaVuSans.ttf");

type PlotResult = Result<(), Box<dyn std::error::Error>>;

const SIZE: (u32, u32) = (900, 600);

fn palette(i: usize) -> RGBColor {
    const C: [RGBColor; 8] = [
        RGBColor(31, 119, 180),
        RGBColor(255, 127, 14),
        RGBColor(44, 160, 44),
        RGBColor(214, 39, 40),
        RGBColor(148, 103, 189),
        RGBColor(140, 86, 75),
        RGBColor(227, 119, 194),
        RGBColor(127, 127, 127),
    ];
    C[i % C.len()]
}

/// Draws every plot into `out`.
///
/// # Errors
/// Font registration or drawing failures.
pub fn all(out: &Path, records: &[Record]) -> PlotResult {
    // Registering twice is harmless (the map entry is replaced).
    plotters::style::register_font("sans-serif", FontStyle::Normal, FONT)
        .map_err(|_| "the bundled font assets/fonts/DejaVuSans.ttf is not a valid font")?;
    let mode = preferred_mode(records);
    time_vs_triangles(&out.join("time_vs_triangles.png"), records, &mode)?;
    time_vs_lights(&out.join("time_vs_lights.png"), records, &mode)?;
    accuracy_cost(&out.join("accuracy_cost.png"), records)?;
    individual_vs_baked(&out.join("individual_vs_baked.png"), records)?;
    maps_vs_volumes(&out.join("maps_vs_volumes.png"), records)?;
    memory_per_triangle(&out.join("memory_per_triangle.png"), records)?;
    soft_error_vs_time(&out.join("soft_error_vs_time.png"), records)?;
    Ok(())
}

fn memory_per_triangle(path: &Path, records: &[Record]) -> PlotResult {
    let s = crate::matrix::memory_table::plot_points(records);
    let title = "Peak RSS per triangle vs triangles (exact)";
    let axes = (
        "peak RSS, bytes per triangle",
        SeriesLabelPosition::UpperRight,
    );
    per_triangles_log_log(path, title, &s, axes)
}

fn preferred_mode(records: &[Record]) -> String {
    if records.iter().any(|r| r.mode() == Some("robust")) {
        "robust".into()
    } else {
        records
            .iter()
            .find_map(Record::mode)
            .unwrap_or("original")
            .to_owned()
    }
}

/// Points of one line per backend.
type Series = BTreeMap<String, Vec<(f64, f64)>>;

/// `((x min, x max), (y min, y max))` of a series.
type Bounds = ((f64, f64), (f64, f64));

/// Series per backend of (x, median_ms) of the `bench` records of one experiment and mode,
/// with x from `x`.
fn series(
    records: &[Record],
    experiment: &str,
    mode: &str,
    x: fn(&crate::matrix::records::Bench) -> Option<u64>,
) -> Series {
    let mut s = Series::new();
    for r in records
        .iter()
        .filter(|r| r.experiment == experiment && r.mode() == Some(mode))
    {
        let Some(b) = r.bench() else { continue };
        if let (Some(x), Some(y)) = (x(b), b.median_ms) {
            let x = x as f64;
            if x > 0.0 && y > 0.0 {
                s.entry(r.key.backend.clone()).or_default().push((x, y));
            }
        }
    }
    for v in s.values_mut() {
        v.sort_by(|a, b| a.0.total_cmp(&b.0));
    }
    s
}

fn bounds(s: &Series) -> Bounds {
    let pts = s.values().flatten();
    let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    for &(x, y) in pts {
        x0 = x0.min(x);
        x1 = x1.max(x);
        y0 = y0.min(y);
        y1 = y1.max(y);
    }
    if x0 > x1 {
        return ((1.0, 10.0), (0.1, 10.0));
    }
    ((x0, x1.max(x0 * 1.01)), (y0, y1.max(y0 * 1.01)))
}

fn no_data(path: &Path, title: &str) -> PlotResult {
    let root = canvas(path, SIZE)?;
    root.draw_text(
        &format!("{title}: no data in this run"),
        &("sans-serif", 24).into_font().color(&BLACK),
        (40, 280),
    )?;
    root.present()?;
    Ok(())
}

/// The bounds of `s`, or `None` after writing a "no data" image titled `title` to `path`
/// when `s` is empty.
fn bounds_or_no_data(
    path: &Path,
    title: &str,
    s: &Series,
) -> Result<Option<Bounds>, Box<dyn std::error::Error>> {
    if s.is_empty() {
        no_data(path, title)?;
        return Ok(None);
    }
    Ok(Some(bounds(s)))
}

/// A white image of `size` pixels, to be written to `path`.
fn canvas(
    path: &Path,
    size: (u32, u32),
) -> Result<DrawingArea<BitMapBackend<'_>, Shift>, Box<dyn std::error::Error>> {
    let root = BitMapBackend::new(path, size).into_drawing_area();
    root.fill(&WHITE)?;
    Ok(root)
}

/// A chart on `area` with the margins and label areas of every plot.
fn chart_on<'a, 'b>(
    area: &'a DrawingArea<BitMapBackend<'b>, Shift>,
) -> ChartBuilder<'a, 'b, BitMapBackend<'b>> {
    let mut c = ChartBuilder::on(area);
    c.margin(15).x_label_area_size(45).y_label_area_size(70);
    c
}

/// Draws the legend of `chart` at `position`, on white of opacity `opacity`.
fn legend<'a, 'b: 'a, X, Y>(
    chart: &mut ChartContext<'a, BitMapBackend<'b>, Cartesian2d<X, Y>>,
    position: SeriesLabelPosition,
    opacity: f64,
    font_size: u32,
) -> PlotResult
where
    X: Ranged<ValueType = f64>,
    Y: Ranged<ValueType = f64>,
{
    chart
        .configure_series_labels()
        .position(position)
        .background_style(WHITE.mix(opacity))
        .border_style(BLACK)
        .label_font(("sans-serif", font_size))
        .draw()?;
    Ok(())
}

/// One line with point markers per backend of `s`, and their legend at `position`.
fn backend_lines<'a, 'b: 'a, X, Y>(
    chart: &mut ChartContext<'a, BitMapBackend<'b>, Cartesian2d<X, Y>>,
    s: &Series,
    position: SeriesLabelPosition,
) -> PlotResult
where
    X: Ranged<ValueType = f64>,
    Y: Ranged<ValueType = f64>,
{
    for (i, (b, pts)) in s.iter().enumerate() {
        let c = palette(i);
        chart
            .draw_series(LineSeries::new(pts.iter().copied(), c.stroke_width(2)))?
            .label(b.clone())
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], c.stroke_width(2)));
        chart.draw_series(pts.iter().map(|&p| Circle::new(p, 4, c.filled())))?;
    }
    legend(chart, position, 0.8, 16)
}

fn time_vs_triangles(path: &Path, records: &[Record], mode: &str) -> PlotResult {
    let s = series(records, "triangles", mode, |b| b.triangles);
    let title = format!("Silhouette time vs triangles ({mode}, 1 light)");
    let axes = ("median ms", SeriesLabelPosition::UpperLeft);
    per_triangles_log_log(path, &title, &s, axes)
}

/// One line per series of `s` against triangles, both axes logarithmic; `(y_desc, legend)`.
fn per_triangles_log_log(
    path: &Path,
    title: &str,
    s: &Series,
    (y_desc, legend): (&str, SeriesLabelPosition),
) -> PlotResult {
    let Some(((x0, x1), (y0, y1))) = bounds_or_no_data(path, title, s)? else {
        return Ok(());
    };
    let root = canvas(path, SIZE)?;
    let mut chart = chart_on(&root)
        .caption(title, ("sans-serif", 24))
        .build_cartesian_2d(
            (x0 * 0.8..x1 * 1.25).log_scale(),
            (y0 * 0.7..y1 * 1.4).log_scale(),
        )?;
    chart
        .configure_mesh()
        .x_desc("triangles")
        .y_desc(y_desc)
        .x_label_formatter(&tick)
        .y_label_formatter(&tick)
        .label_style(("sans-serif", 14))
        .draw()?;
    backend_lines(&mut chart, s, legend)?;
    root.present()?;
    Ok(())
}

fn time_vs_lights(path: &Path, records: &[Record], mode: &str) -> PlotResult {
    let s = series(records, "lights", mode, |b| b.lights);
    let title = format!("Silhouette time vs lights in one call ({mode})");
    let Some(((x0, x1), (y0, y1))) = bounds_or_no_data(path, &title, &s)? else {
        return Ok(());
    };
    let root = canvas(path, SIZE)?;
    let mut chart = chart_on(&root)
        .caption(&title, ("sans-serif", 24))
        .build_cartesian_2d(x0 - 0.5..x1 + 0.5, (y0 * 0.7..y1 * 1.4).log_scale())?;
    chart
        .configure_mesh()
        .x_desc("lights in one extract call")
        .y_desc("median ms")
        .x_labels(8)
        .x_label_formatter(&|x: &f64| format!("{x:.0}"))
        .y_label_formatter(&tick)
        .label_style(("sans-serif", 14))
        .draw()?;
    backend_lines(&mut chart, &s, SeriesLabelPosition::MiddleRight)?;
    root.present()?;
    Ok(())
}

/// Draws `pts` (a `Vec<(f64, f64)>`) as filled markers: circle, triangle, square or cross by
/// `shape`; evaluates to the series annotation (for `.label`).
macro_rules! markers {
    ($chart:expr, $shape:expr, $pts:expr, $c:expr) => {{
        let c: RGBColor = $c;
        let pts: Vec<(f64, f64)> = $pts;
        match $shape % 4 {
            0 => $chart.draw_series(pts.iter().map(|&p| Circle::new(p, 6, c.filled())))?,
            1 => $chart.draw_series(pts.iter().map(|&p| TriangleMarker::new(p, 8, c.filled())))?,
            2 => $chart
                .draw_series(pts.iter().map(|&p| {
                    EmptyElement::at(p) + Rectangle::new([(-5, -5), (5, 5)], c.filled())
                }))?,
            _ => $chart.draw_series(pts.iter().map(|&p| Cross::new(p, 6, c.stroke_width(3))))?,
        }
    }};
}

/// Sets the legend of a series annotation to the marker of `shape` in colour `c`.
macro_rules! marker_legend {
    ($anno:expr, $shape:expr, $c:expr) => {{
        let c: RGBColor = $c;
        let a = $anno;
        match $shape % 4 {
            0 => a.legend(move |(x, y)| Circle::new((x + 10, y), 6, c.filled())),
            1 => a.legend(move |(x, y)| TriangleMarker::new((x + 10, y), 8, c.filled())),
            2 => a.legend(move |(x, y)| {
                EmptyElement::at((x + 10, y)) + Rectangle::new([(-5, -5), (5, 5)], c.filled())
            }),
            _ => a.legend(move |(x, y)| Cross::new((x + 10, y), 6, c.stroke_width(3))),
        }
    }};
}

/// Mode -> marker shape (original, robust, ordered, exact).
fn mode_shape(m: &str) -> usize {
    match m {
        "original" => 3,
        "robust" => 1,
        "ordered" => 2,
        _ => 0,
    }
}

/// Compact tick labels on log axes: 0.01, 0.1, 1, 10, 1000, 1e6.
fn tick(v: &f64) -> String {
    let a = v.abs();
    if a >= 1e5 {
        format!("{v:.0e}")
    } else if a >= 1.0 || a == 0.0 {
        format!("{v:.0}")
    } else {
        let s = format!("{v:.3}");
        s.trim_end_matches('0').to_owned()
    }
}

/// Time ratio (mode / original on the table-1 scene) against two error counts, one panel
/// each: edges whose sign differs from exact (hard-* scenes), and artifact pixels plus open
/// vertices. Colour = backend, marker = mode.
fn accuracy_cost(path: &Path, records: &[Record]) -> PlotResult {
    // (backend, mode, time ratio, sign differences, artifacts + open vertices)
    let mut pts: Vec<(String, String, f64, f64, f64)> = Vec::new();
    let t1 = |b: &str, m: &str| {
        records
            .iter()
            .filter(|r| r.is("table1", None, b, m))
            .filter_map(Record::bench)
            .find(|x| x.lights == Some(1))
            .and_then(|x| x.median_ms)
    };
    let mut keys: Vec<(String, String)> = records
        .iter()
        .filter(|r| r.experiment == "table1")
        .filter_map(|r| Some((r.key.backend.clone(), r.mode()?.to_owned())))
        .collect();
    keys.sort();
    keys.dedup();
    for (b, m) in keys {
        let (Some(x), Some(o)) = (t1(&b, &m), t1(&b, "original")) else {
            continue;
        };
        let mine = records
            .iter()
            .filter(|r| r.key.backend == b && r.mode() == Some(m.as_str()));
        let (mut signs, mut bad) = (0u64, 0u64);
        for r in mine {
            if r.experiment == "artifacts" {
                bad += r.render().and_then(|x| x.artifact_pixels).unwrap_or(0);
            } else if let (true, Some(a)) = (r.experiment == "accuracy", r.mode_errors()) {
                bad += a.open_vertices.unwrap_or(0);
                signs += a.sign_diff_vs_exact.unwrap_or(0);
            }
        }
        pts.push((b, m, x / o, signs as f64 + 1.0, bad as f64 + 1.0));
    }
    let title = "What accuracy costs (time on sphere-1m; errors on the hard-* scenes)";
    if pts.is_empty() {
        return no_data(path, title);
    }
    let x1 = pts.iter().map(|p| p.2).fold(1.0f64, f64::max) * 1.1;
    let root = canvas(path, (1200, 600))?;
    let root = root.titled(title, ("sans-serif", 22))?;
    let (left, right) = root.split_horizontally(600);
    let mut backends: Vec<String> = pts.iter().map(|p| p.0.clone()).collect();
    backends.dedup();
    for (panel, (desc, pick)) in [
        (&left, ("1 + edges whose sign differs from exact", 3usize)),
        (&right, ("1 + artifact pixels + open vertices", 4usize)),
    ] {
        let y = |p: &(String, String, f64, f64, f64)| if pick == 3 { p.3 } else { p.4 };
        let y1 = pts.iter().map(y).fold(10.0f64, f64::max) * 3.0;
        let mut chart = chart_on(panel).build_cartesian_2d(0.0..x1, (0.8..y1).log_scale())?;
        chart
            .configure_mesh()
            .x_desc("silhouette time / original (same backend)")
            .y_desc(desc)
            .y_label_formatter(&tick)
            .label_style(("sans-serif", 14))
            .draw()?;
        for (i, b) in backends.iter().enumerate() {
            let c = palette(i);
            for m in ["original", "robust", "ordered", "exact"] {
                let mine: Vec<(f64, f64)> = pts
                    .iter()
                    .filter(|p| &p.0 == b && p.1 == m)
                    .map(|p| (p.2, y(p)))
                    .collect();
                let anno = markers!(chart, mode_shape(m), mine, c);
                // Left panel: colours (backends); right panel: markers (modes).
                if pick == 3 && m == "exact" {
                    anno.label(b.clone())
                        .legend(move |(x, y)| Circle::new((x + 10, y), 6, c.filled()));
                }
            }
        }
        if pick == 4 {
            for m in ["original", "robust", "ordered", "exact"] {
                let anno = markers!(chart, mode_shape(m), Vec::new(), BLACK);
                marker_legend!(anno.label(m), mode_shape(m), BLACK);
            }
        }
        let position = if pick == 3 {
            SeriesLabelPosition::MiddleMiddle
        } else {
            SeriesLabelPosition::LowerMiddle
        };
        legend(&mut chart, position, 0.85, 15)?;
    }
    root.present()?;
    Ok(())
}

/// Individual objects against the same triangles in fewer objects: the ratio
/// individual / baked per backend, one marker per scene pair.
fn individual_vs_baked(path: &Path, records: &[Record]) -> PlotResult {
    const PAIRS: [(&str, &str, &str, &str); 4] = [
        (
            "bunnies-10-individual",
            "bunnies-10-baked",
            "table2",
            "10 bunnies / baked",
        ),
        (
            "spheres-10-individual",
            "spheres-10-baked",
            "table2",
            "10 spheres / baked",
        ),
        (
            "spheres-100x1k",
            "sphere-100k",
            "table3",
            "100 x 1k / one 100k",
        ),
        (
            "spheres-100x10k",
            "sphere-1m",
            "table3",
            "100 x 10k / one 1M",
        ),
    ];
    let mode = preferred_mode(records);
    let ms = |exp: &str, scene: &str, b: &str| {
        records
            .iter()
            .find(|r| r.is(exp, Some(scene), b, &mode))
            .and_then(|r| r.bench()?.median_ms)
    };
    let mut backends: Vec<String> = Vec::new();
    for r in records
        .iter()
        .filter(|r| r.experiment == "table2" || r.experiment == "table3")
    {
        if !backends.contains(&r.key.backend) {
            backends.push(r.key.backend.clone());
        }
    }
    // (backend index, pair index, ratio)
    let mut pts = Vec::new();
    for (bi, b) in backends.iter().enumerate() {
        for (pi, (ind, baked, exp, _)) in PAIRS.iter().enumerate() {
            if let (Some(i), Some(k)) = (ms(exp, ind, b), ms(exp, baked, b)) {
                if i > 0.0 && k > 0.0 {
                    pts.push((bi, pi, i / k));
                }
            }
        }
    }
    let title = format!("Individual objects vs the same triangles baked ({mode}): time ratio");
    if pts.is_empty() {
        return no_data(path, &title);
    }
    let lo = (pts.iter().map(|p| p.2).fold(1.0f64, f64::min) - 0.15).max(0.0);
    let hi = pts.iter().map(|p| p.2).fold(1.0f64, f64::max) + 0.35;
    let root = canvas(path, SIZE)?;
    let n = backends.len();
    let names = backends.clone();
    let mut chart = chart_on(&root)
        .caption(&title, ("sans-serif", 20))
        .build_cartesian_2d(-0.5..n as f64 - 0.5, lo..hi)?;
    chart
        .configure_mesh()
        .disable_x_mesh()
        .x_labels(n)
        .x_label_formatter(&move |x: &f64| {
            let i = x.round();
            if (x - i).abs() < 0.01 && i >= 0.0 {
                names.get(i as usize).cloned().unwrap_or_default()
            } else {
                String::new()
            }
        })
        .y_labels(12)
        .y_label_formatter(&|y: &f64| format!("{y:.2}"))
        .x_desc("backend")
        .y_desc("individual ms / baked ms (> 1: many objects cost more)")
        .label_style(("sans-serif", 14))
        .draw()?;
    chart.draw_series(LineSeries::new(
        vec![(-0.5, 1.0), (n as f64 - 0.5, 1.0)],
        BLACK.mix(0.5).stroke_width(1),
    ))?;
    for (pi, (_, _, _, label)) in PAIRS.iter().enumerate() {
        let c = palette(pi);
        let dx = (pi as f64 - 1.5) * 0.15;
        let mine: Vec<(f64, f64)> = pts
            .iter()
            .filter(|p| p.1 == pi)
            .map(|p| (p.0 as f64 + dx, p.2))
            .collect();
        let anno = markers!(chart, pi, mine, c);
        marker_legend!(anno.label(*label), pi, c);
    }
    legend(&mut chart, SeriesLabelPosition::UpperRight, 0.85, 15)?;
    root.present()?;
    Ok(())
}

/// Artifact share against frame time, log-log: each technique of the volumes-against-maps
/// table (volumes per mode and pipeline, maps per size and filter with Bevy's bias and tuned),
/// its frame times summed and its artifact pixels over all pixels, over the table's scenes.
/// A share of 0 is drawn at the axis floor.
fn maps_vs_volumes(path: &Path, records: &[Record]) -> PlotResult {
    const FLOOR: f64 = 1e-6;
    let pts = crate::matrix::maps_table::plot_points(records);
    let title = "Artifact share against frame time: volumes and shadow maps";
    if pts.is_empty() {
        return no_data(path, title);
    }
    let x0 = pts.iter().map(|p| p.2).fold(f64::INFINITY, f64::min);
    let x1 = pts.iter().map(|p| p.2).fold(0.0f64, f64::max);
    let y1 = pts.iter().map(|p| p.3).fold(FLOOR * 10.0, f64::max);
    let root = canvas(path, (1200, 800))?;
    let mut chart = chart_on(&root)
        .caption(title, ("sans-serif", 24))
        .build_cartesian_2d(
            (x0 * 0.7..x1 * 1.6).log_scale(),
            (FLOOR * 0.5..y1 * 3.0).log_scale(),
        )?;
    chart
        .configure_mesh()
        .x_desc("frame ms, summed over the scenes (median of each)")
        .y_desc("artifact pixels / pixels (0 drawn at 1e-6)")
        .x_labels(12)
        .x_label_formatter(&tick)
        .y_label_formatter(&|v: &f64| format!("{v:.0e}"))
        .label_style(("sans-serif", 14))
        .draw()?;
    for (i, kind) in ["volumes", "map", "map tuned"].iter().enumerate() {
        let c = palette(i);
        let mine: Vec<(f64, f64, String)> = pts
            .iter()
            .filter(|p| p.1 == *kind)
            .map(|p| (p.2, p.3.max(FLOOR), short_label(&p.0)))
            .collect();
        let xy: Vec<(f64, f64)> = mine.iter().map(|p| (p.0, p.1)).collect();
        let name = match *kind {
            "volumes" => "volumes",
            "map" => "maps, Bevy's bias",
            _ => "maps, bias tuned with hindsight",
        };
        let anno = markers!(chart, i, xy, c);
        marker_legend!(anno.label(name), i, c);
        chart.draw_series(mine.iter().map(|(x, y, l)| {
            EmptyElement::at((*x, *y))
                + Text::new(
                    l.clone(),
                    (9, -14),
                    ("sans-serif", 13).into_font().color(&c),
                )
        }))?;
    }
    legend(&mut chart, SeriesLabelPosition::UpperRight, 0.85, 15)?;
    root.present()?;
    Ok(())
}

/// Visibility error against frame time, log-log: one series per technique of the soft-shadow
/// table (volumes per `--light-samples` and the plan's choice, circles; PCSS per map size,
/// crosses), one point per scene and light size. An error of 0 is drawn at the axis floor.
fn soft_error_vs_time(path: &Path, records: &[Record]) -> PlotResult {
    const FLOOR: f64 = 1e-5;
    let series = crate::matrix::soft_table::plot_points(records);
    let title = "Soft shadows: mean visibility error against frame time";
    let all = || series.iter().flat_map(|s| s.2.iter());
    if all().next().is_none() {
        return no_data(path, title);
    }
    let x0 = all().map(|p| p.0).fold(f64::INFINITY, f64::min);
    let x1 = all().map(|p| p.0).fold(0.0f64, f64::max);
    let y0 = all().map(|p| p.1.max(FLOOR)).fold(f64::INFINITY, f64::min);
    let y1 = all().map(|p| p.1).fold(FLOOR * 10.0, f64::max);
    let root = canvas(path, (1200, 800))?;
    let mut chart = chart_on(&root)
        .caption(title, ("sans-serif", 24))
        .build_cartesian_2d(
            (x0 * 0.7..x1 * 1.6).log_scale(),
            (y0 * 0.5..y1 * 2.0).log_scale(),
        )?;
    chart
        .configure_mesh()
        .x_desc("frame ms (median), one point per scene and light size")
        .y_desc("mean |visibility - true visibility| over the penumbra")
        .x_labels(12)
        .x_label_formatter(&tick)
        .y_label_formatter(&|v: &f64| format!("{v:.0e}"))
        .label_style(("sans-serif", 14))
        .draw()?;
    for (i, (label, pcss, pts)) in series.iter().enumerate() {
        let c = palette(i);
        let shape = if *pcss { 3 } else { 0 };
        let xy: Vec<(f64, f64)> = pts.iter().map(|&(x, y)| (x, y.max(FLOOR))).collect();
        let anno = markers!(chart, shape, xy, c);
        marker_legend!(anno.label(label.clone()), shape, c);
    }
    legend(&mut chart, SeriesLabelPosition::UpperRight, 0.85, 15)?;
    root.present()?;
    Ok(())
}

/// `volumes, GPU pipeline, exact` -> `gpu exact`; `map 2048 pcf, Bevy's bias` -> `2048 pcf`.
fn short_label(label: &str) -> String {
    let l = label
        .replace("volumes, GPU pipeline, ", "gpu ")
        .replace("volumes, host pipeline ", "host ");
    let l = l.strip_prefix("map ").unwrap_or(&l);
    l.split(',').next().unwrap_or(l).to_owned()
}
