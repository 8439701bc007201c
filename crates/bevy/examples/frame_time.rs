//! Frame time of one Bevy scene with the plugin's shadow volumes against the same scene with
//! Bevy's own shadow maps, in the same process, rounds alternating.
//!
//! `cargo run --release --example frame_time -- [--frames N] [--rounds R] [--size WxH]`
//! (from `crates/bevy`). The scene: the bundled bunny on a floor, one point light, Bevy's
//! default camera (MSAA 4x) drawing into an image without a window. Each frame is timed from
//! its update to the device going idle. Prints each round's median and one JSON line.

#[path = "../tests/common/mod.rs"]
mod common;

use std::time::Instant;

use bevy::prelude::*;
use common::Driver;
use shadowvol_bevy::ShadowVolumeLight;

const USAGE: &str = "usage: frame_time [--frames N] [--rounds R] [--size WxH]";

fn arg<T: std::str::FromStr>(v: Option<String>, what: &str) -> Result<T, String> {
    v.as_deref()
        .ok_or_else(|| format!("{what} needs a value\n{USAGE}"))?
        .parse()
        .map_err(|_| format!("{what}: not a number\n{USAGE}"))
}

fn main() -> std::process::ExitCode {
    match run() {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("frame_time: {e}");
            std::process::ExitCode::FAILURE
        }
    }
}

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn run() -> Result<(), String> {
    let (mut frames, mut rounds, mut size) = (60usize, 3usize, (1280u32, 720u32));
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        match a.as_str() {
            "--frames" => frames = arg(args.next(), "--frames")?,
            "--rounds" => rounds = arg(args.next(), "--rounds")?,
            "--size" => {
                let s: String = arg(args.next(), "--size")?;
                let (w, h) = s.split_once('x').ok_or(format!("--size WxH, not {s}"))?;
                size = (
                    w.parse().map_err(|_| format!("--size: bad width {w}"))?,
                    h.parse().map_err(|_| format!("--size: bad height {h}"))?,
                );
            }
            "-h" | "--help" => {
                println!("{USAGE}");
                return Ok(());
            }
            _ => return Err(format!("unknown argument {a}\n{USAGE}")),
        }
    }
    if frames == 0 || rounds == 0 {
        return Err("--frames and --rounds must be at least 1".into());
    }
    let mut d = Driver::new(size.0, size.1);
    d.spawn_caster(common::floor(), Transform::IDENTITY);
    let bunny = common::bunny();
    let at = common::stand_on_floor(&bunny, 2.0);
    d.spawn_caster(bunny, at);
    let light = d.spawn_light(Vec3::new(2.0, 5.0, 1.0), Color::WHITE);
    let mut results = Vec::new();
    for round in 0..rounds {
        for volumes in [true, false] {
            {
                let world = d.world();
                let mut e = world.entity_mut(light);
                if volumes {
                    e.insert(ShadowVolumeLight);
                } else {
                    e.remove::<ShadowVolumeLight>();
                    e.get_mut::<PointLight>()
                        .ok_or("no light")?
                        .shadow_maps_enabled = true;
                }
            }
            for _ in 0..5 {
                d.update(); // warm-up: pipelines, uploads
            }
            let mut ms: Vec<f64> = (0..frames)
                .map(|_| {
                    let t = Instant::now();
                    d.update();
                    t.elapsed().as_secs_f64() * 1e3
                })
                .collect();
            let m = median(&mut ms);
            let what = if volumes { "volumes" } else { "maps" };
            println!("round {round}: {what:8} median {m:.2} ms over {frames} frames");
            results.push((volumes, m));
        }
    }
    if let Some(e) = d.stats().error() {
        return Err(e);
    }
    let mut v: Vec<f64> = results.iter().filter(|r| r.0).map(|r| r.1).collect();
    let mut m: Vec<f64> = results.iter().filter(|r| !r.0).map(|r| r.1).collect();
    let (v, m) = (median(&mut v), median(&mut m));
    println!(
        "{{\"width\":{},\"height\":{},\"frames\":{frames},\"rounds\":{rounds},\"volumes_ms\":{v:.3},\"maps_ms\":{m:.3},\"ratio\":{:.3}}}",
        size.0,
        size.1,
        v / m
    );
    Ok(())
}
