//! PNG plots of the matrix records, drawn with plotters and a bundled font (DejaVu Sans, see
//! assets/fonts), so no system font library is needed.

use plotters::prelude::*;
use serde_json::Value;
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
pub fn all(out: &Path, records: &[Value]) -> PlotResult {
    // Registering twice is harmless (the map entry is replaced).
    plotters::style::register_font("sans-serif", FontStyle::Normal, FONT)
        .map_err(|_| "the bundled font assets/fonts/DejaVuSans.ttf is not a valid font")?;
    let mode = preferred_mode(records);
    time_vs_triangles(&out.join("time_vs_triangles.png"), records, &mode)?;
    time_vs_lights(&out.join("time_vs_lights.png"), records, &mode)?;
    accuracy_cost(&out.join("accuracy_cost.png"), records)?;
    individual_vs_baked(&out.join("individual_vs_baked.png"), records)?;
    Ok(())
}

fn preferred_mode(records: &[Value]) -> String {
    if records.iter().any(|r| r["mode"] == "robust") {
        "robust".into()
    } else {
        records
            .iter()
            .find_map(|r| r["mode"].as_str())
            .unwrap_or("original")
            .to_owned()
    }
}

/// Series per backend of (x, median_ms) for one experiment and mode.
fn series(
    records: &[Value],
    experiment: &str,
    mode: &str,
    x_key: &str,
) -> BTreeMap<String, Vec<(f64, f64)>> {
    let mut s: BTreeMap<String, Vec<(f64, f64)>> = BTreeMap::new();
    for r in records
        .iter()
        .filter(|r| r["experiment"] == experiment && r["mode"] == mode)
    {
        if let (Some(b), Some(x), Some(y)) = (
            r["backend"].as_str(),
            r[x_key].as_f64(),
            r["median_ms"].as_f64(),
        ) {
            if x > 0.0 && y > 0.0 {
                s.entry(b.to_owned()).or_default().push((x, y));
            }
        }
    }
    for v in s.values_mut() {
        v.sort_by(|a, b| a.0.total_cmp(&b.0));
    }
    s
}

fn bounds(s: &BTreeMap<String, Vec<(f64, f64)>>) -> ((f64, f64), (f64, f64)) {
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
    let root = BitMapBackend::new(path, SIZE).into_drawing_area();
    root.fill(&WHITE)?;
    root.draw_text(
        &format!("{title}: no data in this run"),
        &("sans-serif", 24).into_font().color(&BLACK),
        (40, 280),
    )?;
    root.present()?;
    Ok(())
}

fn time_vs_triangles(path: &Path, records: &[Value], mode: &str) -> PlotResult {
    let s = series(records, "triangles", mode, "triangles");
    let title = format!("Silhouette time vs triangles ({mode}, 1 light)");
    if s.is_empty() {
        return no_data(path, &title);
    }
    let ((x0, x1), (y0, y1)) = bounds(&s);
    let root = BitMapBackend::new(path, SIZE).into_drawing_area();
    root.fill(&WHITE)?;
    let mut chart = ChartBuilder::on(&root)
        .caption(&title, ("sans-serif", 24))
        .margin(15)
        .x_label_area_size(45)
        .y_label_area_size(70)
        .build_cartesian_2d(
            (x0 * 0.8..x1 * 1.25).log_scale(),
            (y0 * 0.7..y1 * 1.4).log_scale(),
        )?;
    chart
        .configure_mesh()
        .x_desc("triangles")
        .y_desc("median ms")
        .label_style(("sans-serif", 14))
        .draw()?;
    for (i, (b, pts)) in s.iter().enumerate() {
        let c = palette(i);
        chart
            .draw_series(LineSeries::new(pts.iter().copied(), c.stroke_width(2)))?
            .label(b.clone())
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], c.stroke_width(2)));
        chart.draw_series(pts.iter().map(|&p| Circle::new(p, 4, c.filled())))?;
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .label_font(("sans-serif", 16))
        .draw()?;
    root.present()?;
    Ok(())
}

fn time_vs_lights(path: &Path, records: &[Value], mode: &str) -> PlotResult {
    let s = series(records, "lights", mode, "lights");
    let title = format!("Silhouette time vs lights in one call ({mode})");
    if s.is_empty() {
        return no_data(path, &title);
    }
    let ((x0, x1), (y0, y1)) = bounds(&s);
    let root = BitMapBackend::new(path, SIZE).into_drawing_area();
    root.fill(&WHITE)?;
    let mut chart = ChartBuilder::on(&root)
        .caption(&title, ("sans-serif", 24))
        .margin(15)
        .x_label_area_size(45)
        .y_label_area_size(70)
        .build_cartesian_2d(x0 - 0.5..x1 + 0.5, (y0 * 0.7..y1 * 1.4).log_scale())?;
    chart
        .configure_mesh()
        .x_desc("lights")
        .y_desc("median ms")
        .label_style(("sans-serif", 14))
        .draw()?;
    for (i, (b, pts)) in s.iter().enumerate() {
        let c = palette(i);
        chart
            .draw_series(LineSeries::new(pts.iter().copied(), c.stroke_width(2)))?
            .label(b.clone())
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], c.stroke_width(2)));
        chart.draw_series(pts.iter().map(|&p| Circle::new(p, 4, c.filled())))?;
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .label_font(("sans-serif", 16))
        .draw()?;
    root.present()?;
    Ok(())
}

/// Time ratio (mode / original on the table-1 scene) against artifacts + open vertices.
fn accuracy_cost(path: &Path, records: &[Value]) -> PlotResult {
    let mut pts: Vec<(String, String, f64, f64)> = Vec::new();
    let t1 = |b: &str, m: &str| {
        records
            .iter()
            .find(|r| {
                r["experiment"] == "table1"
                    && r["backend"] == b
                    && r["mode"] == m
                    && r["lights"].as_u64() == Some(1)
            })
            .and_then(|r| r["median_ms"].as_f64())
    };
    let mut keys: Vec<(String, String)> = records
        .iter()
        .filter(|r| r["experiment"] == "table1")
        .filter_map(|r| {
            Some((
                r["backend"].as_str()?.to_owned(),
                r["mode"].as_str()?.to_owned(),
            ))
        })
        .collect();
    keys.sort();
    keys.dedup();
    for (b, m) in keys {
        let (Some(x), Some(o)) = (t1(&b, &m), t1(&b, "original")) else {
            continue;
        };
        let bad: u64 = records
            .iter()
            .filter(|r| r["backend"] == b.as_str() && r["mode"] == m.as_str())
            .map(|r| match r["experiment"].as_str() {
                Some("artifacts") => r["artifact_pixels"].as_u64().unwrap_or(0),
                Some("accuracy") => r["open_vertices"].as_u64().unwrap_or(0),
                _ => 0,
            })
            .sum();
        pts.push((b, m, x / o, bad as f64 + 1.0));
    }
    let title = "What accuracy costs: time / original vs artifact pixels + open vertices";
    if pts.is_empty() {
        return no_data(path, title);
    }
    let x1 = pts.iter().map(|p| p.2).fold(1.0f64, f64::max) * 1.15;
    let y1 = pts.iter().map(|p| p.3).fold(10.0f64, f64::max) * 3.0;
    let root = BitMapBackend::new(path, SIZE).into_drawing_area();
    root.fill(&WHITE)?;
    let mut chart = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 20))
        .margin(15)
        .x_label_area_size(45)
        .y_label_area_size(70)
        .build_cartesian_2d(0.0..x1, (0.8..y1).log_scale())?;
    chart
        .configure_mesh()
        .x_desc("silhouette time / original (same backend)")
        .y_desc("1 + artifact pixels + open vertices")
        .label_style(("sans-serif", 14))
        .draw()?;
    let backends: Vec<String> = {
        let mut v: Vec<String> = pts.iter().map(|p| p.0.clone()).collect();
        v.dedup();
        v
    };
    for (i, b) in backends.iter().enumerate() {
        let c = palette(i);
        let mine: Vec<&(String, String, f64, f64)> = pts.iter().filter(|p| &p.0 == b).collect();
        chart
            .draw_series(mine.iter().map(|p| Circle::new((p.2, p.3), 6, c.filled())))?
            .label(b.clone())
            .legend(move |(x, y)| Circle::new((x + 10, y), 5, c.filled()));
        chart.draw_series(mine.iter().map(|p| {
            Text::new(
                p.1.clone(),
                (p.2, p.3),
                ("sans-serif", 13).into_font().color(&BLACK),
            )
        }))?;
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .label_font(("sans-serif", 16))
        .draw()?;
    root.present()?;
    Ok(())
}

/// Individual objects against the same triangles baked into one mesh.
fn individual_vs_baked(path: &Path, records: &[Value]) -> PlotResult {
    const PAIRS: [(&str, &str, &str); 4] = [
        ("bunnies-10-individual", "bunnies-10-baked", "table2"),
        ("spheres-10-individual", "spheres-10-baked", "table2"),
        ("spheres-100x1k", "sphere-100k", "table3"),
        ("spheres-100x10k", "sphere-1m", "table3"),
    ];
    let mode = preferred_mode(records);
    let ms = |exp: &str, scene: &str, b: &str| {
        records
            .iter()
            .find(|r| {
                r["experiment"] == exp
                    && r["scene"] == scene
                    && r["backend"] == b
                    && r["mode"] == mode.as_str()
            })
            .and_then(|r| r["median_ms"].as_f64())
    };
    let mut backends: Vec<String> = records
        .iter()
        .filter(|r| r["experiment"] == "table2" || r["experiment"] == "table3")
        .filter_map(|r| r["backend"].as_str().map(str::to_owned))
        .collect();
    backends.sort();
    backends.dedup();
    let mut pts = Vec::new();
    for b in &backends {
        for (ind, baked, exp) in PAIRS {
            if let (Some(i), Some(k)) = (ms(exp, ind, b), ms(exp, baked, b)) {
                pts.push((b.clone(), ind, k, i));
            }
        }
    }
    let title = format!("Individual objects vs one baked mesh ({mode})");
    if pts.is_empty() {
        return no_data(path, &title);
    }
    let lo = pts.iter().map(|p| p.2.min(p.3)).fold(f64::MAX, f64::min) * 0.6;
    let hi = pts.iter().map(|p| p.2.max(p.3)).fold(0.0f64, f64::max) * 1.6;
    let root = BitMapBackend::new(path, SIZE).into_drawing_area();
    root.fill(&WHITE)?;
    let mut chart = ChartBuilder::on(&root)
        .caption(&title, ("sans-serif", 22))
        .margin(15)
        .x_label_area_size(45)
        .y_label_area_size(70)
        .build_cartesian_2d((lo..hi).log_scale(), (lo..hi).log_scale())?;
    chart
        .configure_mesh()
        .x_desc("baked ms")
        .y_desc("individual objects ms")
        .label_style(("sans-serif", 14))
        .draw()?;
    chart.draw_series(LineSeries::new(
        vec![(lo, lo), (hi, hi)],
        BLACK.mix(0.4).stroke_width(1),
    ))?;
    for (i, b) in backends.iter().enumerate() {
        let c = palette(i);
        let mine: Vec<_> = pts.iter().filter(|p| &p.0 == b).collect();
        chart
            .draw_series(mine.iter().map(|p| Circle::new((p.2, p.3), 6, c.filled())))?
            .label(b.clone())
            .legend(move |(x, y)| Circle::new((x + 10, y), 5, c.filled()));
        chart.draw_series(mine.iter().map(|p| {
            Text::new(
                p.1.to_owned(),
                (p.2, p.3),
                ("sans-serif", 12).into_font().color(&BLACK),
            )
        }))?;
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .label_font(("sans-serif", 16))
        .draw()?;
    root.present()?;
    Ok(())
}
