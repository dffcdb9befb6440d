//! The `shmgen` command line.

use anyhow::Result;
use clap::{Parser, Subcommand};
use shmgen::eval::{self, Align, Condition, EvalOptions, Mask};
use shmgen::export::{self, ExportOptions, Format};
use shmgen::pipeline::{self, RunOptions, Shard};
use shmgen::preview::{self, PreviewOptions, Size, WatchOptions};
use shmgen::recipe::Recipe;
use std::path::PathBuf;
use std::process::ExitCode;

/// Counts what each thread allocates, so a recipe's script has a memory budget.
#[global_allocator]
static ALLOCATOR: shmgen::recipe::CountingAllocator = shmgen::recipe::CountingAllocator;

/// Most worker threads `--threads` accepts.
const MAX_THREADS: usize = 1024;
/// Most samples and views a preview sheet shows.
const MAX_PREVIEW: u64 = 100;

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
        /// Worker threads, 1 to 1024 (default: every core). Does not change a single output byte.
        #[arg(long, value_parser = parse_threads)]
        threads: Option<usize>,
        /// Render only samples with index ≡ K (mod N), e.g. 0/4. Shards share one --out (or
        /// write one each, gathered by `shmgen merge`). With --frames-per-unit, the units
        /// dealt out are frame ranges of the sequence samples instead.
        #[arg(long, default_value = "0/1")]
        shard: Shard,
        /// Split each sequence sample (dataset.sequence) into units of F consecutive frames,
        /// each rendered, committed and resumed alone, and dealt out by --shard (unit u =
        /// sample × units per sample + range, taken by shard u mod N): one long sequence
        /// spread over N nodes. Every file has the bytes a run without it gives. Default:
        /// whole samples.
        #[arg(long, value_name = "F")]
        frames_per_unit: Option<u32>,
        /// Replace a different dataset already in --out: says first what differs and how many
        /// finished samples it deletes; refused while another process writes that dataset.
        /// Never needed to resume the same dataset.
        #[arg(long)]
        force: bool,
        /// No progress output.
        #[arg(long)]
        quiet: bool,
    },
    /// Re-render a small preview sheet whenever the recipe or a file it uses changes.
    Watch {
        /// The recipe, e.g. scripts/quickstart.rhai.
        recipe: PathBuf,
        /// Override a recipe parameter declared with param("name", default). Repeatable.
        #[arg(long = "set", value_name = "NAME=VALUE", value_parser = parse_set)]
        sets: Vec<(String, String)>,
        /// Samples in the sheet, from the first (1 to 100).
        #[arg(long, default_value_t = 4, value_parser = clap::value_parser!(u64).range(1..=MAX_PREVIEW))]
        samples: u64,
        /// Views of each sample, 1 to 100 (default: up to 4).
        #[arg(long, value_parser = clap::value_parser!(u32).range(1..=MAX_PREVIEW as i64))]
        views: Option<u32>,
        /// Longer side of each image in pixels, at most (never above the recipe's resolution;
        /// smaller when the sheet would not fit 1920×1080).
        #[arg(
            long,
            value_name = "PX",
            default_value_t = 240,
            conflicts_with = "scale",
            value_parser = clap::value_parser!(u32).range(1..)
        )]
        size: u32,
        /// Scale the recipe's resolution instead, e.g. 0.25.
        #[arg(long, value_parser = parse_scale)]
        scale: Option<f64>,
        /// Where to write the sheet (default: <recipe stem>.preview.png next to the recipe).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Also serve the sheet as a self-refreshing page at http://127.0.0.1:PORT/ (0 picks a
        /// free port).
        #[arg(long, value_name = "PORT", conflicts_with = "once")]
        serve: Option<u16>,
        /// Write one sheet and exit (non-zero if the recipe is broken).
        #[arg(long)]
        once: bool,
    },
    /// Validate a recipe and estimate the run time and disk size of its dataset, from a
    /// small timed render (nothing is kept).
    Check {
        /// The recipe, e.g. scripts/quickstart.rhai.
        recipe: PathBuf,
        /// Override a recipe parameter declared with param("name", default). Repeatable.
        #[arg(long = "set", value_name = "NAME=VALUE", value_parser = parse_set)]
        sets: Vec<(String, String)>,
        /// Worker threads for the timed render and the estimate, 1 to 1024 (default: every core).
        #[arg(long, value_parser = parse_threads)]
        threads: Option<usize>,
    },
    /// Convert a finished dataset for other tools (nothing is rendered again): nerfstudio
    /// scenes, COLMAP text models, WebDataset tar shards, 16-bit millimetre depth PNGs or
    /// optical flow (KITTI PNG and Middlebury .flo).
    Export {
        /// The dataset folder (`shmgen run --out`), finished.
        dataset: PathBuf,
        /// nerfstudio, colmap, webdataset, png16 or flow.
        #[arg(long, value_parser = str::parse::<Format>)]
        format: Format,
        /// The folder to create (it must not exist; it appears only when complete).
        #[arg(long)]
        out: PathBuf,
        /// webdataset: views per tar shard (default: near-equal shards, at least 16 or one
        /// per view, at most 1000 views each, so every DataLoader worker gets shards).
        #[arg(long, value_name = "N", value_parser = clap::value_parser!(u64).range(1..))]
        shard_size: Option<u64>,
        /// Copy images instead of hard-linking them to the dataset's.
        #[arg(long)]
        copy: bool,
        /// nerfstudio, colmap: also make frames of augmented copies of views.
        #[arg(long)]
        with_copies: bool,
    },
    /// Check a dataset as received: every file the manifest lists is read, as `export` and
    /// `eval` read them (no link followed, regular files only), and compared with the size
    /// and BLAKE3 hash the manifest records. Exits non-zero if any differs.
    Verify {
        /// The dataset folder, finished.
        dataset: PathBuf,
    },
    /// Gather the folders shards wrote on different nodes (`run --shard K/N --out PART`) into
    /// one dataset, byte for byte what a single run writes. Every part must be the same
    /// dataset; a sample in several parts must be identical there. Files are hard-linked
    /// where possible, else copied, every byte checked against its recorded hash.
    Merge {
        /// The dataset folder to create, or a partial dataset of the same run to add to.
        out: PathBuf,
        /// Folders `shmgen run --shard` wrote (finished or not); never written to.
        #[arg(required = true)]
        parts: Vec<PathBuf>,
    },
    /// How far a dataset folder is: samples done per shard, shards running now (host, pid)
    /// or left stale, which to resubmit, samples/s and time left. Exit code: 0 complete,
    /// 2 incomplete and nothing running (resubmit), 3 incomplete and running (wait), 1 error.
    Status {
        /// The dataset folder (`shmgen run --out`), finished or not.
        dataset: PathBuf,
        /// Print the status as JSON.
        #[arg(long)]
        json: bool,
        /// List shards of N (default: the count of the shards running, else of the lock files
        /// left, else 1).
        #[arg(long, value_name = "N", value_parser = clap::value_parser!(u64).range(1..))]
        shards: Option<u64>,
    },
    /// Score predictions against a finished dataset: depth metrics (AbsRel, SqRel, RMSE,
    /// RMSE log, δ), Chamfer distance and F-score of surfaces, flow and displacement EPE,
    /// sensor histories and point tracks (RMSE, TAP-Vid δ_avg, occlusion, average Jaccard).
    /// Exit code: 0 every prediction asked for was scored, 2 some were not (missing
    /// predictions, truth the dataset lacks, nothing to score: all listed), 1 an error.
    Eval {
        /// The dataset folder, finished.
        dataset: PathBuf,
        /// Predictions mirroring the dataset's samples/ folder (e.g. 0000/000003_01.depth.exr).
        predictions: PathBuf,
        /// Also write the report as JSON to this file.
        #[arg(long)]
        json: Option<PathBuf>,
        /// Per-image alignment of depth: none, median, lstsq or lstsq_shift.
        #[arg(long, default_value = "none", value_parser = str::parse::<Align>)]
        align: Align,
        /// Depth pixels scored: structure (mask > 0) or valid (all with true depth).
        #[arg(long, default_value = "structure", value_parser = str::parse::<Mask>)]
        mask: Mask,
        /// F-score threshold τ in metres.
        #[arg(long, value_name = "METRES", default_value_t = 0.01)]
        fscore_threshold: f64,
        /// Points sampled on each mesh (true and predicted) for Chamfer distance and F-score.
        #[arg(long, value_name = "N", default_value_t = 100_000, value_parser = clap::value_parser!(u64).range(1..=100_000_000))]
        surface_samples: u64,
        /// Score only the views whose JSON record has FIELD (a dotted path) equal to VALUE,
        /// e.g. scene.structures.0.material.prompt="A photo of cracked timber for
        /// construction"; repeatable: conditions on one field are alternatives (--where
        /// sample=3 --where sample=7), conditions on different fields must all hold.
        #[arg(long = "where", value_name = "FIELD=VALUE", value_parser = str::parse::<Condition>)]
        selection: Vec<Condition>,
    },
}

fn parse_scale(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(x) if x > 0.0 && x <= 1.0 => Ok(x),
        _ => Err(format!(
            "--scale {s}: expected a number in (0, 1], e.g. 0.25"
        )),
    }
}

fn parse_threads(s: &str) -> Result<usize, String> {
    match s.parse::<usize>() {
        Ok(n) if (1..=MAX_THREADS).contains(&n) => Ok(n),
        _ => Err(format!(
            "expected a whole number of worker threads from 1 to {MAX_THREADS} (this machine has {} cores; leave --threads out to use them all)",
            std::thread::available_parallelism().map_or(1, |n| n.get())
        )),
    }
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
            // Recipe errors come formatted, with their source line; every other error gets
            // the same "error:" heading.
            if e.downcast_ref::<shmgen::recipe::RecipeError>().is_some() {
                eprintln!("{e:#}");
            } else {
                eprintln!("error: {}", shmgen::words::short_numbers(&format!("{e:#}")));
            }
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
            frames_per_unit,
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
                    frames_per_unit,
                    force,
                    quiet,
                },
            )?;
            let rate = summary.pairs as f64 / summary.seconds.max(1e-9);
            println!(
                "done: {} {} rendered ({} already present), {} image/depth pairs in {:.2} s = {rate:.1} pairs/s, {:.1} MB written to {}{}",
                summary.rendered,
                if frames_per_unit.is_some() {
                    "units of frames"
                } else {
                    "samples"
                },
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
        Command::Watch {
            recipe,
            sets,
            samples,
            views,
            size,
            scale,
            out,
            serve,
            once,
        } => preview::watch(&WatchOptions {
            recipe,
            sets,
            preview: PreviewOptions {
                samples,
                views,
                size: scale.map_or(Size::MaxSide(size), Size::Scale),
            },
            out,
            serve,
            once,
        }),
        Command::Check {
            recipe,
            sets,
            threads,
        } => preview::check(&recipe, &sets, threads),
        Command::Export {
            dataset,
            format,
            out,
            shard_size,
            copy,
            with_copies,
        } => {
            let started = std::time::Instant::now();
            let summary = export::export(
                &dataset,
                &ExportOptions {
                    format,
                    out: out.clone(),
                    shard_size: shard_size.map(|n| usize::try_from(n).unwrap_or(usize::MAX)),
                    copy,
                    with_copies,
                },
            )?;
            if summary.saturated > 0 {
                eprintln!(
                    "warning: {} depth pixels beyond 65.535 m were written as 65535 mm",
                    summary.saturated
                );
            }
            if summary.flow_out_of_range > 0 {
                eprintln!(
                    "warning: {} flow vectors beyond ±512 px were written invalid in the KITTI PNGs (the .flo files keep them)",
                    summary.flow_out_of_range
                );
            }
            if summary.raised > 0 {
                eprintln!(
                    "warning: {} depth pixels closer than 0.5 mm were written as 1 mm (0 means no surface)",
                    summary.raised
                );
            }
            println!(
                "done: {} views exported as {} in {:.2} s to {} ({} files linked, {} copied, {} written)",
                summary.views,
                format.name(),
                started.elapsed().as_secs_f64(),
                out.display(),
                summary.linked,
                summary.copied,
                summary.written
            );
            Ok(())
        }
        Command::Verify { dataset } => verify(&dataset),
        Command::Merge { out, parts } => merge(&out, &parts),
        Command::Status {
            dataset,
            json,
            shards,
        } => status(&dataset, json, shards),
        Command::Eval {
            dataset,
            predictions,
            json,
            align,
            mask,
            fscore_threshold,
            surface_samples,
            selection,
        } => {
            let report = eval::evaluate(
                &dataset,
                &predictions,
                &EvalOptions {
                    align,
                    mask,
                    fscore_threshold,
                    surface_samples: usize::try_from(surface_samples).unwrap_or(usize::MAX),
                    json: json.clone(),
                    selection,
                },
            )?;
            for warning in report.warnings() {
                eprintln!("warning: {warning}");
            }
            print!("{}", report.text());
            println!("{}", report.summary());
            if let Some(path) = json {
                report.write_json(&path)?;
            }
            if report.complete {
                Ok(())
            } else {
                std::process::exit(i32::from(eval::EXIT_PARTIAL))
            }
        }
    }
}

/// `shmgen merge`: one summary line saying what came from where and whether the dataset is
/// complete.
fn merge(out: &std::path::Path, parts: &[PathBuf]) -> Result<()> {
    let summary = export::merge(out, parts)?;
    let from: Vec<String> = summary
        .taken
        .iter()
        .map(|(part, n)| format!("{n} from {}", part.display()))
        .collect();
    let state = match summary.first_missing {
        None => format!("complete: all {} samples", summary.total),
        Some(first) => format!(
            "incomplete: {} of {} samples missing (first: sample {first}); `shmgen run` with the parts' recipe and --out {} renders the rest",
            summary.missing,
            summary.total,
            out.display()
        ),
    };
    println!(
        "merged into {}: {} ({} already there, {} duplicates identical in several parts taken once; {} units of frames of unfinished samples; {} files linked, {} copied; {} files or lines of unfinished samples in the parts ignored); {state}",
        out.display(),
        from.join(", "),
        summary.already,
        summary.duplicates,
        summary.units,
        summary.linked,
        summary.copied,
        summary.unfinished,
    );
    Ok(())
}

/// `shmgen verify`: a line per file that differs, then a summary; an error if any did.
fn verify(dataset: &std::path::Path) -> Result<()> {
    let started = std::time::Instant::now();
    let verified = shmgen::dataset::verify(dataset)?;
    for line in verified.failed.iter().chain(&verified.extra) {
        eprintln!("{line}");
    }
    let gb = verified.bytes as f64 / 1e9;
    let seconds = started.elapsed().as_secs_f64();
    if !verified.failed.is_empty() || !verified.extra.is_empty() {
        anyhow::bail!(
            "{}: {} of {} files differ from what manifest.jsonl records, and {} entries it does not list are there (listed above)",
            dataset.display(),
            verified.failed.len(),
            verified.files,
            verified.extra.len()
        );
    }
    if verified.unrecorded > 0 {
        println!(
            "{} files ({gb:.2} GB) read in {seconds:.1} s; {} of them have no hash in manifest.jsonl (written by an older shmgen): they are regular files inside the dataset, their content is unchecked",
            verified.files, verified.unrecorded
        );
    } else {
        println!(
            "verified: {} files ({gb:.2} GB) match the sizes and BLAKE3 hashes manifest.jsonl records, in {seconds:.1} s",
            verified.files
        );
    }
    Ok(())
}

/// `shmgen status`: prints the status, then exits with its code (0 complete, 2 incomplete,
/// 3 running); an error returns, to exit 1 like every command's.
fn status(dataset: &std::path::Path, json: bool, shards: Option<u64>) -> Result<()> {
    use std::io::Write;
    let status = pipeline::status(dataset, shards)?;
    if json {
        println!("{}", serde_json::to_string_pretty(&status)?);
    } else {
        print!("{}", status_text(dataset, &status));
    }
    std::io::stdout().flush()?;
    match status.exit_code() {
        0 => Ok(()),
        code => std::process::exit(i32::from(code)),
    }
}

/// Partly done samples listed by `status` (all of them with `--json`).
const PARTIAL_SHOWN: usize = 10;

/// The status for people.
fn status_text(dataset: &std::path::Path, s: &pipeline::Status) -> String {
    use std::fmt::Write;
    let mut t = String::new();
    let state = match s.exit_code() {
        pipeline::EXIT_COMPLETE => "complete",
        pipeline::EXIT_RUNNING => "incomplete, running",
        _ => "incomplete, nothing running",
    };
    let _ = writeln!(
        t,
        "{}: dataset {} (seed {}): {} of {} samples ({state})",
        dataset.display(),
        s.name,
        s.seed,
        s.done,
        s.samples
    );
    if !s.shard_counts_seen.is_empty() {
        let counts: Vec<String> = s.shard_counts_seen.iter().map(u64::to_string).collect();
        let _ = writeln!(
            t,
            "shard counts used (lock files and marks in .partial/): {}",
            counts.join(", ")
        );
    }
    match s.frames_per_unit {
        Some(f) => {
            let _ = writeln!(
                t,
                "shards of {}, counted in units of {f} frames:",
                s.shard_count
            );
        }
        None => {
            let _ = writeln!(t, "shards of {}:", s.shard_count);
        }
    }
    for shard in &s.shards {
        let _ = writeln!(
            t,
            "  {}/{}: {} of {}{}",
            shard.index,
            s.shard_count,
            shard.done,
            shard.expected,
            if shard.running { " (running)" } else { "" }
        );
    }
    for partial in s.partial.iter().take(PARTIAL_SHOWN) {
        let _ = writeln!(
            t,
            "  sample {}: {} of {} frames",
            partial.sample, partial.frames_done, partial.frames
        );
    }
    if s.partial.len() > PARTIAL_SHOWN {
        let more = s.partial.len() - PARTIAL_SHOWN;
        let _ = writeln!(
            t,
            "  ... and {more} more samples partly done (--json lists them)"
        );
    }
    for lock in &s.locks {
        let _ = writeln!(t, "lock {}: {}: {}", lock.shard, lock.state, lock.note);
    }
    if s.unreadable_lines > 0 {
        let _ = writeln!(
            t,
            "manifest.jsonl: {} lines ignored (torn by a killed run, or not parsing)",
            s.unreadable_lines
        );
    }
    if !s.resubmit.is_empty() {
        let shards: Vec<String> = s
            .resubmit
            .iter()
            .map(|k| format!("--shard {k}/{}", s.shard_count))
            .collect();
        let units = (s.frames_per_unit).map_or(String::new(), |f| {
            format!(" (each with --frames-per-unit {f})")
        });
        let _ = writeln!(t, "resubmit: {}{units}", shards.join(" "));
        let _ = writeln!(t, "slurm: --array={}", s.resubmit_array);
    }
    if let Some(p) = &s.progress {
        let _ = writeln!(
            t,
            "progress: {:.2} samples/s over the latest {} samples (file times), {} left at that rate; last sample {} ago",
            p.samples_per_second,
            p.measured_over,
            duration(p.seconds_left),
            duration(p.seconds_since_last)
        );
    }
    t
}

/// Seconds as "1 h 02 min", "3 min 05 s" or "12 s".
fn duration(seconds: f64) -> String {
    let s = seconds.max(0.0).round() as u64;
    match (s / 3600, s / 60 % 60, s % 60) {
        (0, 0, s) => format!("{s} s"),
        (0, m, s) => format!("{m} min {s:02} s"),
        (h, m, _) => format!("{h} h {m:02} min"),
    }
}
