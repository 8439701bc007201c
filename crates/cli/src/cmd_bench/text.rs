//! The text output of `shadowvol bench`.

use super::Report;
use shadowvol::CliError;
use std::io::Write;

/// Writes `r` as text: the scene, each light count's floor, the build timing, one line per
/// record, samples against their point lights, light scaling and the host.
pub(super) fn print_text(r: &Report, out: &mut dyn Write) -> Result<(), CliError> {
    if let Some(first) = r.records.first() {
        writeln!(
            out,
            "scene {}: {} triangles, {} edges, {} object(s); {} frames",
            first.scene, first.triangles, first.edges, first.objects, r.schedule
        )?;
    }
    for f in &r.floors {
        writeln!(
            out,
            "floor, {} light(s): {:.3} ms (p10 {:.3}, p90 {:.3}; reads {:.1} MB, writes {:.1} MB)",
            f.lights,
            f.floor_ms,
            f.floor_p10_ms,
            f.floor_p90_ms,
            f.floor_bytes_read as f64 / 1e6,
            f.floor_bytes_written as f64 / 1e6
        )?;
    }
    if let Some(b) = &r.build {
        writeln!(
            out,
            "build, {} triangles: {:.1} ms median of {} (min {:.1}); reading its {:.1} MB: {:.2} ms; {:.0}x the read, {} threads",
            b.triangles,
            b.median_ms,
            b.runs,
            b.min_ms,
            b.input_bytes as f64 / 1e6,
            b.read_ms,
            b.ratio,
            b.threads
        )?;
    }
    writeln!(
        out,
        "{:8} {:9} {:>6} {:>10} {:>10} {:>10} {:>8} {:>10}  details",
        "backend", "mode", "lights", "median_ms", "p10_ms", "p90_ms", "x floor", "uncertain"
    )?;
    for rec in &r.records {
        let level = rec
            .details
            .get("simd_level")
            .and_then(|v| v.as_str())
            .map(|s| format!("simd_level={s} "))
            .unwrap_or_default();
        let table = format!("table={:.1}MB", rec.table_bytes as f64 / 1e6);
        writeln!(
            out,
            "{:8} {:9} {:>6} {:10.3} {:10.3} {:10.3} {:8.2} {:10}  {level}{table}",
            rec.backend,
            rec.mode,
            rec.lights,
            rec.median_ms,
            rec.p10_ms,
            rec.p90_ms,
            rec.floor_ratio,
            rec.uncertain
        )?;
    }
    // Samples against their point lights.
    for rec in &r.records {
        if let (Some(ratio), Some(point)) = (rec.samples_vs_point, rec.point_median_ms) {
            writeln!(
                out,
                "{} {}: {} light(s) as {} samples (radius {:?}) / as point lights ({point:.3} \
                 ms) = {ratio:.2}",
                rec.backend,
                rec.mode,
                rec.light_samples.len(),
                rec.lights,
                rec.light_radii
            )?;
        }
    }
    // Light scaling: each light count's median over the first count's, per backend and mode.
    let counted = || r.records.iter().filter(|x| !x.point_reference);
    if r.floors.len() > 1 {
        let base = r.floors[0].lights;
        for rec in counted().filter(|x| x.lights != base) {
            if let Some(b) = counted()
                .find(|x| x.lights == base && x.backend == rec.backend && x.mode == rec.mode)
            {
                writeln!(
                    out,
                    "{} {}: {} lights / {base} = {:.2}",
                    rec.backend,
                    rec.mode,
                    rec.lights,
                    rec.median_ms / b.median_ms
                )?;
            }
        }
    }
    writeln!(
        out,
        "host: {} ({} cores), {}, {}, git {}",
        r.host.cpu, r.host.cores, r.host.rustc, r.host.profile, r.host.git_rev
    )?;
    Ok(())
}
