//! `shadowvol backends`: which backends can start here.

use serde::Serialize;
use shadowvol::{backends, CliError, Format};
use shadowvol_silhouette::BackendError;
use std::io::Write;
use std::sync::mpsc;
use std::time::Duration;

/// The long help of the subcommand.
pub const LONG_ABOUT: &str =
    "List every registered backend (cpu, simd, wgpu, opencl, vulkan), try to start \
                  it, and print its device or the reason it can't start.\n\n\
                  JSON: [{\"name\": \"cpu\", \"available\": true, \"device\": \"...\", \
                  \"reason\": null}, ...]; device is null when unavailable, reason is null when \
                  available.";

#[derive(Debug, clap::Args)]
pub struct Args {
    /// Output format.
    #[arg(long, value_enum, default_value_t = Format::Text)]
    format: Format,
}

/// One row of the JSON output (the contract: exactly these fields, extend only).
#[derive(Debug, Serialize)]
struct Row {
    name: &'static str,
    available: bool,
    device: Option<String>,
    reason: Option<String>,
}

/// How long one backend may take to start before it is reported as unavailable.
const START_TIMEOUT: Duration = Duration::from_secs(60);

/// Starts every backend on its own thread (in parallel; a backend that hangs in its driver
/// cannot hang the command) and reports each in registry order. Each thread that reported is
/// joined, so that no driver is still tearing down a thread while the process exits.
fn rows() -> Vec<Row> {
    let pending: Vec<_> = backends()
        .into_iter()
        .map(|entry| {
            let (tx, rx) = mpsc::channel();
            let thread = std::thread::spawn(move || {
                let result = entry.start().map(|b| b.info().device);
                let _ = tx.send(result);
            });
            (entry.name, rx, thread)
        })
        .collect();
    pending
        .into_iter()
        .map(|(name, rx, thread)| {
            let result = match rx.recv_timeout(START_TIMEOUT) {
                Ok(result) => {
                    // It has sent its result: only its exit is left.
                    let _ = thread.join();
                    result
                }
                Err(_) => Err(BackendError::Unavailable {
                    backend: name,
                    reason: format!("did not start within {} s", START_TIMEOUT.as_secs()),
                }),
            };
            match result {
                Ok(device) => Row {
                    name,
                    available: true,
                    device: Some(device),
                    reason: None,
                },
                Err(e) => Row {
                    name,
                    available: false,
                    device: None,
                    reason: Some(match e {
                        BackendError::Unavailable { reason, .. } => reason,
                        other => other.to_string(),
                    }),
                },
            }
        })
        .collect()
}

pub fn run(args: &Args, out: &mut dyn Write) -> Result<(), CliError> {
    let rows = rows();
    match args.format {
        Format::Json => {
            serde_json::to_writer(&mut *out, &rows).map_err(|e| CliError::Output(e.into()))?;
            writeln!(out)?;
        }
        Format::Text => {
            let width = rows.iter().map(|r| r.name.len()).max().unwrap_or(4).max(7);
            writeln!(
                out,
                "{:width$}  {:11}  device / reason",
                "backend", "status"
            )?;
            for r in &rows {
                let (status, what) = if r.available {
                    ("available", r.device.as_deref().unwrap_or(""))
                } else {
                    ("unavailable", r.reason.as_deref().unwrap_or(""))
                };
                writeln!(out, "{:width$}  {status:11}  {what}", r.name)?;
            }
        }
    }
    Ok(())
}
