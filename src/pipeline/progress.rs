//! Progress reporting: a bar with ETA on a terminal, plain lines otherwise.

use indicatif::{ProgressBar, ProgressStyle};
use std::io::IsTerminal;
use std::sync::Mutex;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant};

pub enum Progress {
    Bar(ProgressBar),
    Lines {
        what: &'static str,
        noun: &'static str,
        total: u64,
        done: AtomicU64,
        start: Instant,
        last: Mutex<Instant>,
    },
    Quiet,
}

impl Progress {
    /// Progress of `what` ("validating", "rendering") `total` things called `noun` ("samples",
    /// "units of frames").
    pub fn new(what: &'static str, noun: &'static str, total: u64, quiet: bool) -> Self {
        if quiet || total == 0 {
            return Progress::Quiet;
        }
        if std::io::stderr().is_terminal() {
            let bar = ProgressBar::new(total);
            bar.set_style(
                ProgressStyle::with_template("{spinner} {msg} [{elapsed_precise}] {bar:40} {pos}/{len} {prefix}, {per_sec}, ETA {eta}")
                    .expect("valid template"),
            );
            bar.set_message(what);
            bar.set_prefix(noun);
            bar.enable_steady_tick(Duration::from_millis(200));
            Progress::Bar(bar)
        } else {
            let now = Instant::now();
            eprintln!("{what}: {total} {noun}");
            Progress::Lines {
                what,
                noun,
                total,
                done: AtomicU64::new(0),
                start: now,
                last: Mutex::new(now),
            }
        }
    }

    pub fn sample_done(&self) {
        match self {
            Progress::Bar(bar) => bar.inc(1),
            Progress::Lines {
                what,
                noun,
                total,
                done,
                start,
                last,
            } => {
                let done = done.fetch_add(1, Ordering::Relaxed) + 1;
                let mut last = last.lock().unwrap();
                if done == *total || last.elapsed() >= Duration::from_secs(5) {
                    *last = Instant::now();
                    let secs = start.elapsed().as_secs_f64();
                    let eta = secs / done as f64 * (total - done) as f64;
                    eprintln!(
                        "{what}: {done}/{total} {noun} ({:.0}%), {secs:.1} s elapsed, ETA {eta:.0} s",
                        100.0 * done as f64 / *total as f64
                    );
                }
            }
            Progress::Quiet => {}
        }
    }

    pub fn finish(&self) {
        if let Progress::Bar(bar) = self {
            bar.finish_and_clear();
        }
    }
}
