//! Time of a frame analysis against model size: space trusses of 10 to 10⁵ members solved by
//! the dense and the sparse Cholesky (dense only while it takes under a few seconds); then a
//! whole sample's frame work, analysis plus tessellation of every deformed member
//! (`build::mesh_frame`, as a render does it for a 960-pixel, 60° camera framing the truss), in
//! CPU time of the thread (the build machine is shared: wall time would count other jobs), with
//! the triangles made and the process's peak resident memory after it (this table comes first,
//! smallest model first, so the peak is that of the largest model meshed so far); then the six
//! lowest natural modes (dense eigensolver) of trusses up to its limit. Prints tables; asserts
//! nothing.
//!
//!     cargo bench --bench frames

use shmgen::build::{frame_radius, mesh_frame};
use shmgen::mechanics::frame::{Solver, space_truss};
use shmgen::scene::FrameSpec;
use std::time::Instant;

/// CPU seconds this thread has used.
fn thread_cpu_seconds() -> f64 {
    let mut t = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: clock_gettime writes one timespec, which `t` is.
    let status = unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut t) };
    assert_eq!(status, 0, "clock_gettime(CLOCK_THREAD_CPUTIME_ID)");
    t.tv_sec as f64 + t.tv_nsec as f64 * 1e-9
}

/// Peak resident memory of the process so far, MB.
fn peak_rss_mb() -> f64 {
    // SAFETY: getrusage fills one rusage, which `usage` is; all-zero is a valid rusage.
    let mut usage: libc::rusage = unsafe { std::mem::zeroed() };
    assert_eq!(unsafe { libc::getrusage(libc::RUSAGE_SELF, &mut usage) }, 0);
    usage.ru_maxrss as f64 / 1024.0
}

/// Least CPU time of `runs` calls of `f`, seconds.
fn best_cpu_of(runs: usize, f: impl Fn()) -> f64 {
    (0..runs)
        .map(|_| {
            let t = thread_cpu_seconds();
            f();
            thread_cpu_seconds() - t
        })
        .fold(f64::INFINITY, f64::min)
}

/// Analysis plus tessellation of space trusses, CPU time a sample.
fn analysis_and_tessellation() {
    println!("| members | analysis + tessellation (ms CPU) | triangles | peak RSS after (MB) |");
    println!("|---:|---:|---:|---:|");
    for panels in [1, 4, 11, 33, 111, 333, 1111, 11111] {
        let mut frame = FrameSpec::new("space truss");
        frame.model = space_truss(panels);
        // A 960-pixel, 60° camera at the distance that frames the truss: its pixel footprint.
        let distance = frame_radius(&frame) / (30f64).to_radians().sin();
        let footprint = 2.0 * distance * (30f64).to_radians().tan() / 960.0;
        let runs = if panels > 1000 { 3 } else { 10 };
        let triangles = mesh_frame(&frame, footprint)
            .expect("a stable truss")
            .members
            .iter()
            .map(|m| m.mesh.triangles.len())
            .sum::<usize>();
        let t = best_cpu_of(runs, || {
            mesh_frame(&frame, footprint).expect("a stable truss");
        });
        println!(
            "| {} | {:.2} | {triangles} | {:.0} |",
            frame.model.members.len(),
            t * 1e3,
            peak_rss_mb()
        );
    }
}

fn best_of(runs: usize, f: impl Fn()) -> f64 {
    (0..runs)
        .map(|_| {
            let t = Instant::now();
            f();
            t.elapsed().as_secs_f64()
        })
        .fold(f64::INFINITY, f64::min)
}

fn main() {
    // First, while the process's peak memory is still that of the models meshed so far.
    analysis_and_tessellation();
    println!();
    static_analysis();
    natural_modes();
}

/// The six lowest modes of space trusses up to `DENSE_MODES_MAX_DOFS` free DOFs.
fn natural_modes() {
    println!();
    println!("| members | free DOFs | six modes (ms) |");
    println!("|---:|---:|---:|");
    for panels in [1, 4, 11, 33, 67, 133] {
        let model = space_truss(panels);
        let dofs = 3 * model.nodes.len() - 6;
        let runs = if dofs > 500 { 2 } else { 5 };
        let t = best_of(runs, || {
            model.natural_modes(6).expect("a stable truss");
        });
        println!("| {} | {dofs} | {:.1} |", model.members.len(), t * 1e3);
    }
}

fn static_analysis() {
    println!("| members | free DOFs | dense (ms) | sparse (ms) |");
    println!("|---:|---:|---:|---:|");
    for panels in [1, 4, 11, 33, 111, 333, 1111, 11111] {
        let model = space_truss(panels);
        let dofs = 3 * model.nodes.len() - 6;
        let runs = if panels > 1000 { 3 } else { 10 };
        let dense = if dofs <= 3000 {
            let t = best_of(runs, || {
                model.solve_with(Solver::Dense).expect("a stable truss");
            });
            format!("{:.2}", t * 1e3)
        } else {
            "–".into()
        };
        let sparse = best_of(runs, || {
            model.solve_with(Solver::Sparse).expect("a stable truss");
        });
        println!(
            "| {} | {dofs} | {dense} | {:.2} |",
            model.members.len(),
            sparse * 1e3
        );
    }
}
