//! The `vkvcm` command line: parse, call the library, report.

mod cli;

use std::process::ExitCode;

use anyhow::{bail, Result};
use clap::{Parser, Subcommand};

use vkvcm::gpu;

#[derive(Parser)]
#[command(name = "vkvcm", version, about = "Light transport in Vulkan compute shaders: pt, lt, bpt, ppm, bpm, vcm")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// List Vulkan devices and the features vkvcm needs.
    Devices,
    /// Render a scene to an EXR (and optionally a PNG).
    Render(cli::render::RenderArgs),
    /// A reference image: a long render in two independent halves, with its own error
    /// estimate (RMS of the halves' difference / 2) stored in the EXR.
    Reference(cli::converge::ReferenceArgs),
    /// Error vs. render time of estimators against a reference: CSV and a log-log plot.
    Converge(cli::converge::ConvergeArgs),
    /// RMSE, relative MSE, mean bias and max error of a.exr against b.exr (the reference).
    Diff(cli::diff::DiffArgs),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    // Scene loads and BVH builds of more than a second get a progress line.
    vkvcm::activity::set_observer(Box::new(cli::progress::ActivityLines));
    let result = match cli.command {
        Command::Devices => devices(),
        Command::Render(args) => cli::render::render_cmd(args),
        Command::Reference(args) => cli::converge::reference_cmd(args),
        Command::Converge(args) => cli::converge::converge_cmd(args),
        Command::Diff(args) => cli::diff::diff_cmd(args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

fn devices() -> Result<()> {
    let list = gpu::list_devices()?;
    if list.is_empty() {
        bail!("no Vulkan device found");
    }
    for d in &list {
        println!("{}: {} ({}), driver {}, Vulkan {}", d.index, d.name, d.type_name(), d.driver, d.api_version);
        for f in &d.features {
            let mark = if f.present { "yes" } else { "NO " };
            let value = if f.value.is_empty() { String::new() } else { format!(" = {}", f.value) };
            let how = match (f.required, f.present) {
                (false, true) if !f.value.is_empty() => format!("limit: {}", f.without),
                (true, true) => format!("required: {}", f.without),
                (true, false) => format!("REQUIRED, missing: {}; vkvcm cannot run on this device", f.without),
                (false, true) => format!("optional; without it: {}", f.without),
                (false, false) => format!("optional, missing: {}", f.without),
            };
            println!("    {mark} {}{value} ({how})", f.name);
        }
        let missing = d.missing_required();
        if missing.is_empty() {
            println!("    usable by vkvcm");
        } else {
            println!("    NOT usable by vkvcm: it lacks {}", missing.join(", "));
        }
    }
    Ok(())
}
