//! The command line of `cargo xtask matrix`.

use std::path::PathBuf;

pub(super) const USAGE: &str = "\
cargo xtask matrix [--quick] [--out DIR] [--backends LIST] [--modes LIST] [--frames N]
                   [--only maps|memory|soft]

Runs the paper's experiment matrix with the release `shadowvol` binary on every available
backend and writes DIR/tables.md, DIR/results.json, DIR/results.csv and PNG plots.

  --quick          every table and scene, fewer frames and smaller images (about 10 minutes on a
                   2-core machine with lavapipe and PoCL)
  --out DIR        output folder (default: matrix-out)
  --backends LIST  comma-separated backend names (default: all available)
  --modes LIST     comma-separated accuracy modes (default: original,robust,ordered,exact)
  --frames N       timed frames per measurement (default: 30, or 5 with --quick)
  --only maps      only the volumes-against-maps table (every hard-* preset, town,
                   bunnies-10-individual and sphere-1m at 1280x720; maps of 512 to 8192 texels,
                   hard and PCF, Bevy's bias and a bias sweep; about 110 minutes on 2 cores with --frames 10)
  --only soft      only the soft-shadow table (docs/SOFT.md): lights of three sizes (0.01, 0.03
                   and 0.1 of the scene's box for point lights, 0.0047, 0.02 and 0.05 rad for
                   town's sun) on hard-tetrahedron and hard-book-3 (their point lights, with a
                   backdrop), bunny on a floor and town at 960x540; exact volumes at
                   --light-samples 1, 4, 16, 64 and the plan's choice, PCSS maps of 2048 and 4096:
                   error against the true visibility and frame time (town at N = 64 takes about
                   20 s a frame on 2 cores with lavapipe). With --quick, and inside --quick:
                   hard-tetrahedron at 0.03, N = 1 and 16, PCSS 2048, 320x180 (seconds)
  --only memory    only the memory table: peak RSS and prepared bytes per triangle of
                   `silhouette` on every backend and of `render` on each pipeline, on spheres of
                   10^5 to 10^7 triangles (10^5 and 10^6 with --quick)
  --replot DIR     measure nothing: rewrite DIR/tables.md, DIR/results.csv and the plots from
                   DIR/results.json (after a change to the tables or plots)
";

/// The accuracy modes in table order.
pub(super) const MODES: [&str; 4] = ["original", "robust", "ordered", "exact"];

/// Options of one matrix run.
#[derive(Debug, Clone)]
pub(super) struct Options {
    pub quick: bool,
    pub out: PathBuf,
    pub backends: Option<Vec<String>>,
    pub modes: Vec<String>,
    pub frames: u32,
    /// Untimed warm-up frames per measurement (3, or 1 with `--quick`).
    pub warmup: u32,
    /// `--replot DIR`: rewrite the tables and plots of an earlier run.
    pub replot: Option<PathBuf>,
    /// `--only TABLE`: only that table runs.
    pub only: Option<Only>,
}

/// A table that `--only` runs alone.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Only {
    /// The volumes-against-maps table.
    Maps,
    /// The memory table.
    Memory,
    /// The soft-shadow table: volumes against PCSS for lights with a size.
    Soft,
}

/// Parses the arguments after `matrix`; `None` after `--help` (the usage is printed).
///
/// # Errors
/// A message naming the unknown argument, mode or bad value, with the usage.
pub(super) fn parse_args(args: &[String]) -> Result<Option<Options>, String> {
    let mut o = Options {
        quick: false,
        out: PathBuf::from("matrix-out"),
        backends: None,
        modes: MODES.iter().map(|s| (*s).to_owned()).collect(),
        frames: 0,
        warmup: 3,
        replot: None,
        only: None,
    };
    let mut it = args.iter();
    while let Some(a) = it.next() {
        let mut value = |name: &str| crate::next_value(&mut it, name, USAGE);
        match a.as_str() {
            "-h" | "--help" => {
                print!("{USAGE}");
                return Ok(None);
            }
            "--quick" => o.quick = true,
            "--out" => o.out = PathBuf::from(value("--out")?),
            "--replot" => o.replot = Some(PathBuf::from(value("--replot")?)),
            "--only" => {
                let v = value("--only")?;
                o.only = Some(match v.as_str() {
                    "maps" => Only::Maps,
                    "memory" => Only::Memory,
                    "soft" => Only::Soft,
                    _ => {
                        return Err(format!(
                            "--only {v:?}: the tables that run alone are `maps` (volumes against \
                             maps), `memory` and `soft` (volumes against PCSS)"
                        ))
                    }
                });
            }
            "--backends" => {
                o.backends = Some(split_list(&value("--backends")?));
            }
            "--modes" => {
                let modes = split_list(&value("--modes")?);
                for m in &modes {
                    if !MODES.contains(&m.as_str()) {
                        return Err(format!(
                            "unknown mode {m:?} in --modes; expected some of {}",
                            MODES.join(",")
                        ));
                    }
                }
                o.modes = modes;
            }
            "--frames" => {
                let v = value("--frames")?;
                o.frames = v
                    .parse()
                    .ok()
                    .filter(|&n| n > 0)
                    .ok_or_else(|| format!("--frames {v:?}: expected a positive integer"))?;
            }
            other => return Err(format!("unknown argument {other:?}\n\n{USAGE}")),
        }
    }
    if o.frames == 0 {
        o.frames = if o.quick { 5 } else { 30 };
    }
    if o.quick {
        o.warmup = 1;
    }
    Ok(Some(o))
}

fn split_list(s: &str) -> Vec<String> {
    s.split(',')
        .map(|x| x.trim().to_owned())
        .filter(|x| !x.is_empty())
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn args(a: &[&str]) -> Vec<String> {
        a.iter().map(|s| (*s).to_owned()).collect()
    }

    #[test]
    fn args_parse() {
        let o = parse_args(&args(&["--quick", "--modes", "exact"]))
            .unwrap()
            .unwrap();
        assert!(o.quick);
        assert_eq!(o.frames, 5);
        assert_eq!(o.warmup, 1);
        assert_eq!(o.modes, vec!["exact"]);
        let o = parse_args(&args(&["--backends", "cpu, simd,", "--frames", "7"]))
            .unwrap()
            .unwrap();
        assert_eq!(o.backends, Some(vec!["cpu".to_owned(), "simd".to_owned()]));
        assert_eq!((o.frames, o.warmup), (7, 3));
        assert!(parse_args(&args(&["--modes", "fast"])).is_err());
        assert!(parse_args(&args(&["--frames", "0"])).is_err());
        let o = parse_args(&args(&["--only", "soft"])).unwrap().unwrap();
        assert_eq!(o.only, Some(Only::Soft));
        let e = parse_args(&args(&["--out"])).unwrap_err();
        assert!(e.starts_with("--out needs a value"), "{e}");
    }
}
