//! What the benchmarks share: the median they quote and the environment settings they read.
//! Each bench is its own crate and takes this file in with `#[path]`; a bench that uses only
//! one of the two allows the other to be dead.

/// The median of `v` (the upper one of an even count).
pub fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// The whole number in environment variable `name`, or `default` when unset or unreadable.
#[allow(dead_code)]
pub fn setting(name: &str, default: u64) -> u64 {
    std::env::var(name)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

/// One whole quiet run of `recipe` into a fresh temporary folder on `threads` threads.
#[allow(dead_code)]
pub fn run_in_temp(
    recipe: &shmgen::recipe::Recipe,
    threads: usize,
) -> shmgen::pipeline::RunSummary {
    let dir = tempfile::tempdir().unwrap();
    let options = shmgen::pipeline::RunOptions {
        out: dir.path().join("ds"),
        threads: Some(threads),
        shard: shmgen::pipeline::Shard::WHOLE,
        frames_per_unit: None,
        force: false,
        quiet: true,
    };
    shmgen::pipeline::run(recipe, &options).expect("run")
}
