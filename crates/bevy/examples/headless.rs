//! No window: a box on a floor under a point light, with shadow volumes, written to a PNG.
//!
//! `cargo run --example headless -- out.png` (from `crates/bevy`). The camera is Bevy's default
//! (MSAA 4x, TonyMcMapface tonemapping), drawing into an image; frames are driven by hand.

#[path = "../tests/common/mod.rs"]
mod common;

use bevy::core_pipeline::tonemapping::Tonemapping;
use bevy::prelude::*;
use common::Driver;

fn main() -> std::process::ExitCode {
    let mut args = std::env::args().skip(1);
    let out = match (args.next(), args.next()) {
        (Some(a), None) if !a.starts_with('-') => a,
        _ => {
            eprintln!("usage: headless OUT.png\nDraws a box on a floor with shadow volumes, without a window.");
            return std::process::ExitCode::FAILURE;
        }
    };
    let (w, h) = (640, 480);
    let mut d = Driver::new(w, h);
    let camera = d.camera;
    d.world().entity_mut(camera).insert(Tonemapping::default());
    d.world().insert_resource(GlobalAmbientLight::default());
    d.spawn_caster(common::floor(), Transform::IDENTITY);
    d.spawn_caster(common::unit_box(), Transform::from_xyz(-0.3, 0.5, 0.2));
    d.spawn_light(Vec3::new(2.0, 5.0, 1.0), Color::srgb(1.0, 0.95, 0.85));
    for _ in 0..4 {
        d.update();
    }
    let rgba = d.capture();
    if let Some(e) = d.stats().error() {
        eprintln!("headless: {e}");
        return std::process::ExitCode::FAILURE;
    }
    if let Err(e) = image::save_buffer(&out, &rgba, w, h, image::ExtendedColorType::Rgba8) {
        eprintln!("headless: writing {out}: {e}");
        return std::process::ExitCode::FAILURE;
    }
    println!(
        "wrote {out} ({w}x{h}); casters prepared {} time(s)",
        d.stats().prepares()
    );
    std::process::ExitCode::SUCCESS
}
