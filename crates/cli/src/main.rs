//! The `shadowvol` command line.
//!
//! Each subcommand lives in its own module `cmd_<name>.rs` with a clap `Args` struct and a
//! `run(args, out) -> Result<(), CliError>` function. Adding one is three lines here: the `mod`
//! line, a variant of [`Command`] (its doc comment is the short help, `LONG_ABOUT` of the
//! module the long one) and a match arm in [`run`].

use clap::{Parser, Subcommand};
use shadowvol::CliError;
use std::io::Write;
use std::process::ExitCode;

mod build_time;
mod cmd_accuracy;
mod cmd_backends;
mod cmd_baselines;
mod cmd_bench;
mod cmd_render;
mod cmd_scenes;
mod cmd_silhouette;
mod cmd_view;
mod shot;

/// Robust silhouette shadow volumes: silhouette edges with multiplicities on five
/// interchangeable backends (cpu, simd, wgpu, opencl, vulkan), in four accuracy modes.
///
/// Exit codes: 0 success, 1 failure (bad input file, unavailable backend, device error),
/// 2 usage error (bad arguments).
#[derive(Debug, Parser)]
#[command(
    name = "shadowvol",
    version,
    propagate_version = true,
    after_help = shadowvol::INPUT_FORMATS
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

/// `--light-samples` of the commands without a camera (`silhouette`, `bench`).
const SAMPLES_HELP: &str = "Points sampling each light with a size (--light-radius, or a glTF \
    light's own radius), all in one extraction call [default: 16; these commands have no camera, \
    so no plan chooses from a penumbra's width]";

#[derive(Debug, Subcommand)]
enum Command {
    /// List the backends, whether each can start here, its device, or why it can't.
    #[command(long_about = cmd_backends::LONG_ABOUT)]
    Backends(cmd_backends::Args),
    /// Compute the silhouette edges of a mesh, with multiplicities, for one or more lights.
    #[command(
        long_about = cmd_silhouette::LONG_ABOUT,
        after_help = cmd_silhouette::AFTER_HELP,
        mut_arg("light_samples", |a| a.help(SAMPLES_HELP))
    )]
    Silhouette(cmd_silhouette::Args),
    /// Measure what each accuracy mode gets wrong on the hard scenes (open vertices, signs
    /// that differ from exact).
    #[command(long_about = cmd_accuracy::LONG_ABOUT)]
    Accuracy(cmd_accuracy::Args),
    /// Time silhouette extraction per backend and mode on a scene, next to the measured memory
    /// floor (median, p10, p90).
    #[command(
        long_about = cmd_bench::LONG_ABOUT,
        mut_arg("light_samples", |a| a.help(SAMPLES_HELP))
    )]
    Bench(cmd_bench::Args),
    /// Time the seeds' CPU silhouette algorithms (Toy Wars, the thesis) next to our modes.
    #[command(long_about = cmd_baselines::LONG_ABOUT, after_help = cmd_baselines::AFTER_HELP)]
    Baselines(cmd_baselines::Args),
    /// List the scene presets with their objects, triangles and lights.
    #[command(long_about = cmd_scenes::LONG_ABOUT)]
    Scenes(cmd_scenes::Args),
    /// Work with one scene: `scene export NAME OUT.glb` writes it as binary glTF.
    #[command(long_about = cmd_scenes::SCENE_LONG_ABOUT)]
    Scene(cmd_scenes::SceneArgs),
    /// Render a scene with stencil shadow volumes (wgpu, headless) to a PNG; optionally compare
    /// with a ray-traced reference and count artifact pixels.
    #[command(long_about = cmd_render::LONG_ABOUT, after_help = cmd_render::AFTER_HELP)]
    Render(cmd_render::Args),
    /// Open a live window onto a scene: orbit, move the light, switch modes and techniques,
    /// show the volumes.
    #[command(long_about = cmd_view::LONG_ABOUT, after_help = cmd_view::AFTER_HELP)]
    View(cmd_view::Args),
}

fn run(command: Command, out: &mut dyn Write) -> Result<(), CliError> {
    match command {
        Command::Backends(args) => cmd_backends::run(&args, out),
        Command::Silhouette(args) => cmd_silhouette::run(&args, out),
        Command::Accuracy(args) => cmd_accuracy::run(&args, out),
        Command::Bench(args) => cmd_bench::run(&args, out),
        Command::Baselines(args) => cmd_baselines::run(&args, out),
        Command::Scenes(args) => cmd_scenes::run(&args, out),
        Command::Scene(args) => cmd_scenes::run_scene(&args, out),
        Command::Render(args) => cmd_render::run(&args, out),
        Command::View(args) => cmd_view::run(&args, out),
    }
}

fn main() -> ExitCode {
    shadowvol::quiet_without_display();
    // A panic inside a guarded third-party decoder (Draco, on a corrupted stream) is caught by
    // the loader and reported as an error below; its panic message would only be noise.
    let default_hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        if !shadowvol_scenes::in_guarded_decoder() {
            default_hook(info);
        }
    }));
    // Usage errors exit with code 2 inside clap, with its message; --help and --version exit 0.
    let cli = Cli::parse();
    let stdout = std::io::stdout();
    let mut out = std::io::BufWriter::new(stdout.lock());
    let result = run(cli.command, &mut out).and_then(|()| out.flush().map_err(CliError::from));
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) if e.is_broken_pipe() => ExitCode::SUCCESS,
        Err(e) => {
            // Never panic, even when stderr is closed.
            let _ = writeln!(std::io::stderr(), "error: {e}");
            ExitCode::from(e.exit_code())
        }
    }
}
