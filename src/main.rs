//! The `vkvcm` command line: parse, call the library, report.

mod cli;

use std::process::ExitCode;

use anyhow::Result;
use clap::{CommandFactory, Parser, Subcommand};

use cli::exit::{Class, ClassifyExt};

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
    Render(Box<cli::render::RenderArgs>),
    /// Merge the shards of a split render (`render --shard K/N`) into the whole render,
    /// bit for bit what one device renders (docs/distributed.md).
    Merge(cli::merge::MergeArgs),
    /// A reference image: a long render in two independent halves, with its own error
    /// estimate (RMS of the halves' difference / 2) stored in the EXR.
    Reference(cli::converge::ReferenceArgs),
    /// Error vs. render time of estimators against a reference: CSV and a log-log plot.
    Converge(cli::converge::ConvergeArgs),
    /// RMSE, relative MSE, mean bias and max error of a.exr against b.exr (the reference).
    Diff(cli::diff::DiffArgs),
    /// Denoise a render's EXR with Intel Open Image Denoise, guided by its albedo and
    /// normal AOVs (`render --aov albedo,normal`; docs/denoising.md).
    Denoise(cli::denoise::DenoiseArgs),
    /// What a render of a scene would hold and need, before rendering: what the importer
    /// read and skipped, the kernels' features, and each buffer's memory on the device.
    Info(cli::info::InfoArgs),
    /// Print a shell completion script: `vkvcm completions bash > ~/.local/share/bash-completion/completions/vkvcm`.
    Completions {
        #[arg(value_enum)]
        shell: clap_complete::Shell,
    },
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    // Scene loads and BVH builds of more than a second get a progress line (not with
    // --quiet).
    let quiet = matches!(&cli.command, Command::Render(a) if a.quiet);
    if !quiet {
        vkvcm::activity::set_observer(Box::new(cli::progress::ActivityLines));
    }
    let done = |r: Result<()>| r.map(|()| None);
    let result = match cli.command {
        Command::Devices => done(devices()),
        Command::Render(args) => cli::render::render_cmd(*args),
        Command::Merge(args) => done(cli::merge::merge_cmd(args)),
        Command::Reference(args) => done(cli::converge::reference_cmd(args)),
        Command::Converge(args) => done(cli::converge::converge_cmd(args)),
        Command::Diff(args) => done(cli::diff::diff_cmd(args)),
        Command::Info(args) => cli::info::info_cmd(args),
        Command::Denoise(args) => done(cli::denoise::denoise_cmd(args)),
        Command::Completions { shell } => {
            clap_complete::generate(shell, &mut Cli::command(), "vkvcm", &mut std::io::stdout());
            Ok(None)
        }
    };
    match result {
        Ok(None) => ExitCode::SUCCESS,
        Ok(Some(class)) => cli::exit::code(class),
        Err(e) => {
            eprintln!("error: {e:#}");
            cli::exit::code(cli::exit::class_of(&e))
        }
    }
}

fn devices() -> Result<()> {
    let list = gpu::list_devices().class(Class::Device)?;
    if list.is_empty() {
        return Err(anyhow::anyhow!("no Vulkan device found")).class(Class::Device);
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
