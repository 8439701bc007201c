//! `tables.md`'s "Soft shadows: volumes against PCSS": per scene and light size, each
//! technique's visibility error and frame time, and for each PCSS size the cheapest volumes at
//! equal or better mean error with the ratio of their frame times; and the points of
//! `soft_error_vs_time.png`.

use super::plan::{MAP_KEY, SOFT_VOLUMES_KEY};
use super::records::{Record, Render};
use super::tables::fmt_ms;

/// One render of the table.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Row<'a> {
    /// Volumes or PCSS.
    pub pcss: bool,
    /// The render.
    pub render: &'a Render,
}

impl Row<'_> {
    /// The technique in words: `volumes N=16`, `volumes, plan's N`, `PCSS 2048`.
    pub fn label(&self) -> String {
        if self.pcss {
            return format!(
                "PCSS {}",
                self.render
                    .map_size
                    .map_or("?".to_owned(), |s| s.to_string())
            );
        }
        match self.render.light_samples_setting.as_deref() {
            Some("plan") => "volumes, plan's N".to_owned(),
            Some(n) => format!("volumes N={n}"),
            None => "volumes".to_owned(),
        }
    }

    /// The label with the samples the plan chose: `volumes, plan's N (16)`.
    fn label_used(&self) -> String {
        match (
            self.render.light_samples_setting.as_deref(),
            self.render.light_samples_used,
        ) {
            (Some("plan"), Some(n)) => format!("volumes, plan's N ({n})"),
            _ => self.label(),
        }
    }

    /// Median frame time, ms.
    fn ms(&self) -> Option<f64> {
        self.render.frames_median_ms
    }

    /// Mean visibility error over the penumbra.
    fn error(&self) -> Option<f64> {
        self.render.visibility_mean
    }
}

/// The rows of one scene and light size, in the order they ran.
#[derive(Debug, Clone)]
pub(crate) struct Group<'a> {
    /// Scene name.
    pub scene: &'a str,
    /// The radius given, and for point lights its fraction of the scene's box.
    pub radius: (f64, Option<f64>),
    /// Volumes' rows, then PCSS's.
    pub rows: Vec<Row<'a>>,
}

impl Group<'_> {
    /// The radius in words: `0.03 of the box (0.0521)` or `0.02 rad`.
    pub fn radius_label(&self) -> String {
        match self.radius {
            (r, Some(f)) => format!("{f} of the box ({r:.3})"),
            (r, None) => format!("{r} rad"),
        }
    }

    fn volumes(&self) -> impl Iterator<Item = &Row<'_>> {
        self.rows.iter().filter(|r| !r.pcss)
    }

    fn pcss(&self) -> impl Iterator<Item = &Row<'_>> {
        self.rows.iter().filter(|r| r.pcss)
    }
}

/// The `soft` records grouped by scene and light size, in the order they ran.
pub(crate) fn groups(records: &[Record]) -> Vec<Group<'_>> {
    let mut out: Vec<Group<'_>> = Vec::new();
    for x in records.iter().filter(|x| x.experiment == "soft") {
        let Some(render) = x.render() else { continue };
        let Some(radius) = render.light_radius else {
            continue;
        };
        let pcss = x.key.backend == MAP_KEY;
        if !pcss && x.key.backend != SOFT_VOLUMES_KEY {
            continue;
        }
        let row = Row { pcss, render };
        match out
            .iter_mut()
            .find(|g| g.scene == x.key.scene && g.radius.0 == radius)
        {
            Some(g) => g.rows.push(row),
            None => out.push(Group {
                scene: &x.key.scene,
                radius: (radius, render.light_radius_fraction),
                rows: vec![row],
            }),
        }
    }
    for g in &mut out {
        g.rows.sort_by_key(|r| r.pcss);
    }
    out
}

/// What the volumes of one group need to reach one PCSS setting's mean error.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Verdict {
    /// The cheapest volumes whose mean error is at most PCSS's: their label and their frame
    /// time over PCSS's. At a ratio above 1, PCSS wins: every volume setting as fast has a
    /// larger error, and every one as accurate is slower.
    Reached {
        /// The volumes' row label.
        volumes: String,
        /// Volumes' median frame time over PCSS's.
        ratio: f64,
    },
    /// No measured volume setting reaches PCSS's mean error; `pcss_fastest` when PCSS is also
    /// faster than every one of them (PCSS wins outright).
    NoneReaches {
        /// PCSS's frame time is below every volume setting's.
        pcss_fastest: bool,
    },
    /// A figure the comparison needs is missing, in words.
    NotMeasured(&'static str),
}

impl Verdict {
    /// Whether PCSS wins: lower error than any volume setting as fast, at lower time than any
    /// as accurate.
    pub fn pcss_wins(&self) -> bool {
        match self {
            Self::Reached { ratio, .. } => *ratio > 1.0,
            Self::NoneReaches { pcss_fastest } => *pcss_fastest,
            Self::NotMeasured(_) => false,
        }
    }

    /// The table's cell.
    fn words(&self) -> String {
        match self {
            Self::Reached { ratio, .. } if self.pcss_wins() => format!(
                "**PCSS wins** on time: every volume setting as fast has a larger error; equal or lower error costs {ratio:.2}x"
            ),
            Self::Reached { ratio, .. } => {
                format!("volumes win: equal or lower error at {ratio:.2}x PCSS's time")
            }
            Self::NoneReaches { .. } if self.pcss_wins() => {
                "**PCSS wins**: lower error and lower time than every volume N".to_owned()
            }
            Self::NoneReaches { .. } => "no volume N reaches PCSS's error (some are faster)".to_owned(),
            Self::NotMeasured(what) => format!("n/a: {what} missing"),
        }
    }
}

/// The cheapest (median frame time) of `volumes` whose mean error is at most `pcss`'s, and the
/// verdict. Rows without an error or a time take no part.
pub(crate) fn verdict<'a>(pcss: &Row<'a>, volumes: &[Row<'a>]) -> (Verdict, Option<Row<'a>>) {
    let (Some(target), Some(pcss_ms)) = (pcss.error(), pcss.ms()) else {
        return (Verdict::NotMeasured("PCSS's error or time"), None);
    };
    let measured: Vec<(Row<'a>, f64, f64)> = volumes
        .iter()
        .filter_map(|r| Some((*r, r.error()?, r.ms()?)))
        .collect();
    if measured.is_empty() || pcss_ms <= 0.0 {
        return (Verdict::NotMeasured("the volumes' errors or times"), None);
    }
    let cheapest = measured
        .iter()
        .filter(|(_, e, _)| *e <= target)
        .min_by(|a, b| a.2.total_cmp(&b.2));
    match cheapest {
        Some((row, _, ms)) => (
            Verdict::Reached {
                volumes: row.label_used(),
                ratio: ms / pcss_ms,
            },
            Some(*row),
        ),
        None => (
            Verdict::NoneReaches {
                pcss_fastest: measured.iter().all(|(_, _, ms)| pcss_ms < *ms),
            },
            None,
        ),
    }
}

fn error(v: Option<f64>) -> String {
    v.map_or("n/a".to_owned(), |e| format!("{e:.4}"))
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

/// `tables.md`'s section; empty without any `soft` record.
pub(super) fn soft_tables(records: &[Record]) -> String {
    let groups = groups(records);
    let Some(first) = groups.first().and_then(|g| g.rows.first()) else {
        return String::new();
    };
    let mut s = format!(
        "\n## Soft shadows: volumes against PCSS\n\n`render SCENE --light-radius R --reference \
         --frames N` at {}: exact volumes (default pipeline, `--mode exact`) with \
         `--light-samples N` and with the plan's choice, and PCSS as Bevy 0.20 ships it \
         (`--shadows map --map-filter pcss --map-size S`). A point light's radius is a fraction \
         of the diagonal of the scene's caster box (world units in brackets), a directional \
         light's an angle; a preset that mixes the two is rendered with its point lights \
         (`--light`). Error: `|visibility - true visibility|` over the penumbra (pixels \
         whose true visibility is strictly between 0 and 1): the mean over every light's \
         penumbra pixels, and the largest 99th percentile of any light. Sample artifact px: each \
         sample's hard shadow against the reference, summed over the samples. Frame time: median \
         (p10-p90) ms of the frames on the light orbit.\n\n\
         For each PCSS size, the cheapest volumes (by median frame time) whose mean error is at \
         most PCSS's, and their time over PCSS's. **PCSS wins** where that ratio is above 1 (every \
         volume setting as fast has a larger error, every one as accurate is slower) or where no \
         volume setting reaches its error and each is slower.\n\n",
        first.render.size
    );
    s += "| scene | radius | PCSS | PCSS error, ms | cheapest volumes at equal or better error | their error, ms | volumes ms / PCSS ms | verdict |\n|---|---|---|---|---|---|---|---|\n";
    for g in &groups {
        let volumes: Vec<Row<'_>> = g.volumes().copied().collect();
        if g.pcss().next().is_none() {
            s += &format!(
                "| {} | {} | PCSS | n/a | none | n/a | n/a | n/a: no PCSS render (see the failures) |\n",
                g.scene,
                g.radius_label()
            );
        }
        for p in g.pcss() {
            let (v, row) = verdict(p, &volumes);
            let (vol, vol_fig, ratio) = match (&v, row) {
                (Verdict::Reached { volumes, ratio }, Some(r)) => (
                    volumes.clone(),
                    format!("{}, {}", error(r.error()), fmt_ms(r.ms())),
                    format!("{ratio:.2}"),
                ),
                _ => ("none".to_owned(), "n/a".to_owned(), "n/a".to_owned()),
            };
            s += &format!(
                "| {} | {} | {} | {}, {} | {vol} | {vol_fig} | {ratio} | {} |\n",
                g.scene,
                g.radius_label(),
                p.label(),
                error(p.error()),
                fmt_ms(p.ms()),
                v.words(),
            );
        }
    }
    s += "\n| scene | radius | shadows | samples | error mean | error p99 | sample artifact px | penumbra px | frame ms |\n|---|---|---|---|---|---|---|---|---|\n";
    for g in &groups {
        for r in &g.rows {
            let x = r.render;
            s += &format!(
                "| {} | {} | {} | {} | {} | {} | {} | {} | {} |\n",
                g.scene,
                g.radius_label(),
                r.label(),
                if r.pcss {
                    "-".to_owned()
                } else {
                    count(x.light_samples_used)
                },
                error(x.visibility_mean),
                error(x.visibility_p99),
                count(x.sample_artifact_pixels),
                count(x.penumbra_pixels),
                frames(x),
            );
        }
    }
    s += "\n![soft shadows: error against frame time](soft_error_vs_time.png)\n";
    s
}

/// One series of `soft_error_vs_time.png`: the technique's label, whether it is PCSS, and its
/// (median frame ms, mean error) points.
pub(crate) type Series = (String, bool, Vec<(f64, f64)>);

/// The points of `soft_error_vs_time.png`: per technique (row label), one (median frame ms,
/// mean error) per scene and light size where both were measured; volumes first.
pub(crate) fn plot_points(records: &[Record]) -> Vec<Series> {
    let mut out: Vec<Series> = Vec::new();
    for g in groups(records) {
        for r in &g.rows {
            let (Some(ms), Some(e)) = (r.ms(), r.error()) else {
                continue;
            };
            let label = r.label();
            match out.iter_mut().find(|s| s.0 == label) {
                Some(s) => s.2.push((ms, e)),
                None => out.push((label, r.pcss, vec![(ms, e)])),
            }
        }
    }
    out.sort_by_key(|s| s.1);
    out
}
