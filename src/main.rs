//! The `shmgen` command line.

use anyhow::Result;
use clap::{Parser, Subcommand};
use shmgen::pipeline::{self, RunOptions, Shard};
use shmgen::recipe::Recipe;
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Parser)]
#[command(
    name = "shmgen",
    version,
    about = "Synthetic datasets of deformed civil structures from Rhai recipes"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Build (or resume) a dataset from a recipe.
    Run {
        /// The recipe, e.g. scripts/quickstart.rhai.
        recipe: PathBuf,
        /// Dataset folder to create or resume.
        #[arg(long)]
        out: PathBuf,
        /// Override a recipe parameter declared with param("name", default). Repeatable.
        #[arg(long = "set", value_name = "NAME=VALUE", value_parser = parse_set)]
        sets: Vec<(String, String)>,
        /// Worker threads (default: every core). Does not change a single output byte.
        #[arg(long)]
        threads: Option<usize>,
        /// Render only samples with index ≡ K (mod N), e.g. 0/4. Shards share one --out.
        #[arg(long, default_value = "0/1")]
        shard: Shard,
        /// Replace a different dataset already in --out.
        #[arg(long)]
        force: bool,
        /// No progress output.
        #[arg(long)]
        quiet: bool,
    },
}

fn parse_set(s: &str) -> Result<(String, String), String> {
    let (name, value) = s
        .split_once('=')
        .ok_or_else(|| format!("--set {s}: expected NAME=VALUE"))?;
    let name = name.trim();
    if name.is_empty() {
        return Err(format!("--set {s}: the parameter name is empty"));
    }
    Ok((name.to_string(), value.to_string()))
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match execute(cli.command) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("{e:#}");
            ExitCode::FAILURE
        }
    }
}

fn execute(command: Command) -> Result<()> {
    match command {
        Command::Run {
            recipe,
            out,
            sets,
            threads,
            shard,
            force,
            quiet,
        } => {
            let recipe = Recipe::load(&recipe, &sets)?;
            let summary = pipeline::run(
                &recipe,
                &RunOptions {
                    out: out.clone(),
                    threads,
                    shard,
                    force,
                    quiet,
                },
            )?;
            let rate = summary.pairs as f64 / summary.seconds.max(1e-9);
            println!(
                "done: {} samples rendered ({} already present), {} image/depth pairs in {:.2} s = {rate:.1} pairs/s, {:.1} MB written to {}{}",
                summary.rendered,
                summary.skipped,
                summary.pairs,
                summary.seconds,
                summary.bytes as f64 / 1e6,
                out.display(),
                if summary.complete {
                    ""
                } else {
                    " (dataset incomplete: other shards still to run)"
                }
            );
            Ok(())
        }
    }
}
