//! Speed against error for the A1 beams: segments along the length against the largest depth
//! error (against a 4096-segment reference) and the cost per view; and the cost per mesh of
//! each theory. Prints a table; asserts nothing.
//!
//!     cargo bench --bench tessellation

use glam::DVec3;
use shmgen::build::{beam_radius, mesh_beam, problem};
use shmgen::cameras::CameraRig;
use shmgen::mechanics::{Deformation, Load, Support, Target, Theory};
use shmgen::render::{NO_HIT, TraceMesh};
use shmgen::scene::{BeamSpec, Tessellation};
use shmgen::seeds::{Scope, Stream};
use std::time::Instant;

#[path = "support/mod.rs"]
mod support;
use support::median;

/// A1-like beams: length 1 m, paper proportions, peak deflection 0.05 L.
fn beams() -> Vec<(String, BeamSpec)> {
    let mut out = Vec::new();
    for (name, support, at, width, height_ratio) in [
        ("SS mid, slender", Support::SimplySupported, 0.5, 0.02, 0.5),
        (
            "SS quarter, stocky",
            Support::SimplySupported,
            0.25,
            0.25,
            1.5,
        ),
        (
            "cantilever tip, slender",
            Support::Cantilever,
            1.0,
            0.05,
            0.3,
        ),
        (
            "cantilever mid, medium",
            Support::Cantilever,
            0.5,
            0.12,
            1.0,
        ),
    ] {
        let mut b = BeamSpec::rectangular(1.0, width, width * height_ratio);
        b.support = support;
        b.loads = vec![Load::Point { at, force: 1.0 }];
        b.target = Target::Peak { deflection: 0.05 };
        out.push((name.to_string(), b));
    }
    out
}

/// Pixels whose 8 neighbours all see a surface within 1 % of their depth: away from
/// silhouettes and occlusion edges, where a depth difference measures tessellation error.
fn smooth_pixels(depth: &[f32], width: usize) -> Vec<bool> {
    let height = depth.len() / width;
    let mut smooth = vec![false; depth.len()];
    for row in 1..height.saturating_sub(1) {
        for col in 1..width - 1 {
            let z = depth[row * width + col];
            smooth[row * width + col] = z > 0.0
                && (-1..=1).all(|dr: isize| {
                    (-1..=1).all(|dc: isize| {
                        let n = depth
                            [(row as isize + dr) as usize * width + (col as isize + dc) as usize];
                        n > 0.0 && (n - z).abs() < 0.01 * z
                    })
                });
        }
    }
    smooth
}

fn main() {
    let rig = CameraRig::default();
    let views = 6;
    println!(
        "Speed against error, A1 beams (L = 1 m, δ = 0.05 L), 960×960, {views} views each, 1 thread per view"
    );
    println!(
        "depth error: max |z − z_ref| over pixels both see whose reference 3×3 neighbourhood is a continuous surface"
    );
    println!(
        "(occlusion edges excluded; reference: 4096 segments); silhouette: pixels per view whose hit/miss differs"
    );
    let settings: Vec<(String, Tessellation)> = [1, 2, 4, 8, 16, 32, 64]
        .iter()
        .map(|&n| (format!("{n} segments"), Tessellation::Segments(n)))
        .chain([
            (
                "pixel tolerance 1 px".to_string(),
                Tessellation::Pixels(1.0),
            ),
            (
                "pixel tolerance 0.25 px".to_string(),
                Tessellation::Pixels(0.25),
            ),
            (
                "pixel tolerance 0.1 px (default)".to_string(),
                Tessellation::Pixels(0.1),
            ),
            ("paper mesh (12,288 faces)".to_string(), Tessellation::Paper),
        ])
        .collect();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    pool.install(|| {
        for (name, beam) in beams() {
            let footprint = rig.nearest_pixel_footprint(DVec3::ZERO, beam_radius(&beam));
            let mut reference = beam.clone();
            reference.tessellation = Tessellation::Segments(4096);
            let reference_mesh = mesh_beam(&reference, footprint).unwrap().mesh;
            let (centre, radius) = reference_mesh.bounding_sphere().unwrap();
            let cameras: Vec<_> = (0..views).map(|v| rig.draw(&mut Stream::new(1, Scope::View(0, v), "camera"), v, views, centre, radius).unwrap().0).collect();
            let reference_trace = TraceMesh::build(&reference_mesh);
            let truth: Vec<_> = cameras.iter().map(|c| reference_trace.trace(c)).collect();
            println!("\n{name} (pixel at nearest camera {:.2} mm)", footprint * 1e3);
            println!("  {:<36} {:>9} {:>14} {:>11} {:>10} {:>10}", "tessellation", "triangles", "depth err mm", "silhouette", "build ms", "trace ms");
            for (label, tess) in &settings {
                let mut b = beam.clone();
                b.tessellation = *tess;
                let t = Instant::now();
                let mesh = mesh_beam(&b, footprint).unwrap().mesh;
                let trace = TraceMesh::build(&mesh);
                let build_ms = t.elapsed().as_secs_f64() * 1e3;
                let (mut err, mut silhouette, mut times) = (0.0f64, 0usize, Vec::new());
                for (cam, reference) in cameras.iter().zip(&truth) {
                    let t = Instant::now();
                    let g = trace.trace(cam);
                    times.push(t.elapsed().as_secs_f64() * 1e3);
                    let smooth = smooth_pixels(&reference.depth, reference.width as usize);
                    #[expect(
                        clippy::needless_range_loop,
                        reason = "i indexes five per-pixel arrays alike"
                    )]
                    for i in 0..g.depth.len() {
                        match (g.triangle[i] == NO_HIT, reference.triangle[i] == NO_HIT) {
                            (false, false) if smooth[i] => err = err.max(f64::from((g.depth[i] - reference.depth[i]).abs())),
                            (false, false) => {}
                            (true, true) => {}
                            _ => silhouette += 1,
                        }
                    }
                }
                println!("  {label:<36} {:>9} {:>14.4} {:>11} {:>10.2} {:>10.2}", mesh.triangles.len(), err * 1e3, silhouette / views as usize, build_ms, median(times));
            }
        }

        println!("\nCost per mesh of each theory (solve + labels, then + mesh at the default tessellation), median of 200:");
        let (_, stocky) = beams().swap_remove(1);
        let mut cases: Vec<(&str, BeamSpec)> = Vec::new();
        for (name, theory) in [("Euler–Bernoulli", Theory::EulerBernoulli), ("Timoshenko", Theory::Timoshenko), ("auto (both solved)", Theory::Auto)] {
            let mut b = stocky.clone();
            b.theory = theory;
            cases.push((name, b));
        }
        let mut elastica = stocky.clone();
        elastica.support = Support::Cantilever;
        elastica.loads = vec![Load::Point { at: 1.0, force: 1.0 }];
        elastica.target = Target::Peak { deflection: 0.3 };
        elastica.theory = Theory::Elastica;
        cases.push(("elastica (cantilever, δ = 0.3 L)", elastica));
        let mut modal = stocky.clone();
        modal.loads.clear();
        modal.target = Target::Physical;
        modal.vibration = vec![(1, 0.02), (5, 0.002), (100, 0.0001)];
        cases.push(("vibration, modes 1 + 5 + 100", modal));
        for (name, b) in cases {
            let problem = problem(&b);
            let time = |f: &dyn Fn()| {
                median((0..200).map(|_| { let t = Instant::now(); f(); t.elapsed().as_secs_f64() * 1e6 }).collect())
            };
            let solve = time(&|| { std::hint::black_box(Deformation::solve(&problem).unwrap()); });
            let build = time(&|| { std::hint::black_box(mesh_beam(&b, 7e-4).unwrap()); });
            println!("  {name:<34} solve {solve:>7.1} µs   solve + mesh {build:>8.1} µs");
        }
    });
}
