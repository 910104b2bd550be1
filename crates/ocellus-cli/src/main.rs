//! `ocellus`: the command-line program of the ocellus active-vision toolkit.

mod assets;
mod bench;
mod config_file;
mod demo;
mod eval;
mod inputs;
mod overlay;
mod saliency_cmd;

use anyhow::Result;
use clap::{Parser, Subcommand};

/// Fast, biologically inspired active vision: where to look, how it moved, where things are.
#[derive(Parser, Debug)]
#[command(
    name = "ocellus",
    version,
    about = "Fast, biologically inspired active vision for robots: saliency (where to look), and more to come",
    long_about = None
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Run the main capabilities end to end on the built-in images; writes maps and overlays.
    Demo(demo::DemoArgs),
    /// Compute bottom-up saliency maps (Itti-Koch-Niebur) for images or folders of images.
    Saliency(saliency_cmd::SaliencyArgs),
    /// Score saliency maps against human fixation maps (CC, SIM, KL; MIT benchmark definitions).
    Eval(eval::EvalArgs),
    /// Print benchmark figures (median ms per frame, fps on all cores, per stage, peak memory).
    Bench(bench::BenchArgs),
}

fn main() {
    let cli = Cli::parse();
    let r: Result<()> = match cli.command {
        Command::Demo(a) => demo::run(a),
        Command::Saliency(a) => saliency_cmd::run(a),
        Command::Bench(a) => bench::run(a),
        Command::Eval(a) => eval::run(a),
    };
    if let Err(e) = r {
        eprintln!("error: {e:#}");
        std::process::exit(1);
    }
}
