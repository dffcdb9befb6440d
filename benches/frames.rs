//! Time of a frame analysis against model size: space trusses of 10 to 10⁵ members solved by
//! the dense and the sparse Cholesky (dense only while it takes under a few seconds), and the
//! size of the sparse factor; then the six lowest natural modes (dense eigensolver) of trusses
//! up to its limit. Prints tables; asserts nothing.
//!
//!     cargo bench --bench frames

use shmgen::mechanics::frame::{Solver, space_truss};
use std::time::Instant;

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
