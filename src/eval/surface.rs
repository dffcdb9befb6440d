//! Chamfer distance and F-score of a predicted surface (mesh or point cloud) against the
//! ground-truth mesh of a sample.
//!
//! Each direction takes points on one side and measures their exact distance to the other:
//!
//! - P, the predicted points: a cloud's points, or N points sampled on a predicted mesh;
//! - G, N points sampled on the ground-truth mesh;
//! - accuracy a(p) = distance from p to the ground-truth mesh (exact point-to-triangle);
//! - completeness c(g) = distance from g to the prediction (exact point-to-triangle on a mesh,
//!   the nearest point of a cloud).
//!
//! Chamfer-L1 = ½ (mean a + mean c), metres (the accuracy/completeness mean of the DTU and
//! Tanks-and-Temples tradition); Chamfer-L2 = mean a² + mean c², m² (PyTorch3D's and Kaolin's
//! default: squared, mean per direction, summed). F-score at τ (Knapitsch et al., SIGGRAPH
//! 2017; Tatarchenko et al., CVPR 2019): precision = share of P with a < τ, recall = share of
//! G with c < τ, F = 2PR / (P + R), 0 when both are 0.
//!
//! Every metric is finite: a prediction so far from the truth that a distance or its square
//! overflows f64 is refused with the distance (imported files never get there: coordinates
//! beyond ±1e15 are refused when read).
//!
//! Sampling is by area and deterministic: point i of N picks its triangle by the stratified
//! value (i + ½)/N of the cumulative area, and its place in the triangle from the i-th point
//! of the R2 low-discrepancy sequence (Roberts 2018) mapped uniformly by area.

use super::nearest::Nearest;
use crate::geometry::Mesh;
use crate::geometry::import::Surface;
use anyhow::{Result, bail};
use glam::DVec3;
use rayon::prelude::*;

/// The two directions' distances, summarised.
#[derive(Clone, Copy, Debug)]
pub(super) struct SurfaceScore {
    pub(super) accuracy: f64,
    pub(super) completeness: f64,
    pub(super) accuracy_squared: f64,
    pub(super) completeness_squared: f64,
    pub(super) precision: f64,
    pub(super) recall: f64,
}

impl SurfaceScore {
    /// ½ (accuracy + completeness), metres.
    pub(super) fn chamfer_l1(&self) -> f64 {
        0.5 * (self.accuracy + self.completeness)
    }

    /// Mean squared accuracy + mean squared completeness, m².
    pub(super) fn chamfer_l2(&self) -> f64 {
        self.accuracy_squared + self.completeness_squared
    }

    /// The harmonic mean of precision and recall.
    pub(super) fn fscore(&self) -> f64 {
        let sum = self.precision + self.recall;
        if sum > 0.0 {
            2.0 * self.precision * self.recall / sum
        } else {
            0.0
        }
    }
}

/// Scores `prediction` against `truth` with `samples` points per sampled surface and F-score
/// threshold `tau` (metres).
pub(super) fn score(
    prediction: &Surface,
    truth: &Mesh,
    samples: usize,
    tau: f64,
) -> Result<SurfaceScore> {
    let truth_tree = Nearest::triangles(&truth.positions, &truth.triangles);
    let truth_points = sample(truth, samples)?;
    let (predicted_points, predicted_tree) = match prediction {
        Surface::Points(points) => (points.clone(), Nearest::points(points)),
        Surface::Mesh(imported) => (
            sample(&imported.mesh, samples)?,
            Nearest::triangles(&imported.mesh.positions, &imported.mesh.triangles),
        ),
    };
    if predicted_points.is_empty() {
        bail!("the prediction has no points");
    }
    let accuracy = distances(&predicted_points, &truth_tree);
    let completeness = distances(&truth_points, &predicted_tree);
    let mean =
        |d: &[f64], f: &dyn Fn(f64) -> f64| d.iter().map(|&x| f(x)).sum::<f64>() / d.len() as f64;
    let within = |d: &[f64]| d.iter().filter(|&&x| x < tau).count() as f64 / d.len() as f64;
    let score = SurfaceScore {
        accuracy: mean(&accuracy, &|x| x),
        completeness: mean(&completeness, &|x| x),
        accuracy_squared: mean(&accuracy, &|x| x * x),
        completeness_squared: mean(&completeness, &|x| x * x),
        precision: within(&accuracy),
        recall: within(&completeness),
    };
    if !(score.chamfer_l1().is_finite() && score.chamfer_l2().is_finite()) {
        bail!(
            "Chamfer distance not defined: prediction and truth lie {} apart, so the distances or their squares overflow f64 (are the coordinates in metres, in the world frame?)",
            farthest(&accuracy, &completeness)
        );
    }
    Ok(score)
}

/// The largest distance either way, for a message ("up to 1e154 m"); a distance that itself
/// overflowed (the search compares squares) is past 1.3e154 m.
fn farthest(accuracy: &[f64], completeness: &[f64]) -> String {
    let far = accuracy
        .iter()
        .chain(completeness)
        .copied()
        .fold(0.0, f64::max);
    if far.is_finite() {
        format!("up to {far:e} m")
    } else {
        "more than 1e154 m".into()
    }
}

/// Distances from each point to the tree's items, in the points' order (so sums over them
/// have the same bits whatever the threads did).
fn distances(points: &[DVec3], tree: &Nearest) -> Vec<f64> {
    points.par_iter().map(|&p| tree.distance(p)).collect()
}

/// `n` points on `mesh`, uniform by area, deterministic (see the module's documentation).
pub(super) fn sample(mesh: &Mesh, n: usize) -> Result<Vec<DVec3>> {
    let mut cumulative = Vec::with_capacity(mesh.triangles.len());
    let mut total = 0.0;
    for t in 0..mesh.triangles.len() {
        let [a, b, c] = mesh.triangle(t);
        total += 0.5 * (b - a).cross(c - a).length();
        cumulative.push(total);
    }
    // A NaN area (a vertex not finite) has nothing to sample either: spelt out, as the
    // negated `!(total > 0.0)` it replaces meant.
    if total.is_nan() || total <= 0.0 {
        bail!("the mesh has no area to sample");
    }
    // R2 sequence: the plastic number's inverse powers (Roberts 2018).
    let g = 1.324_717_957_244_746_f64;
    let (a1, a2) = (1.0 / g, 1.0 / (g * g));
    Ok((0..n)
        .map(|i| {
            let target = (i as f64 + 0.5) / n as f64 * total;
            let t = cumulative
                .partition_point(|&c| c <= target)
                .min(cumulative.len() - 1);
            let [a, b, c] = mesh.triangle(t);
            let r1 = (0.5 + a1 * i as f64).fract();
            let r2 = (0.5 + a2 * i as f64).fract();
            let s = r1.sqrt();
            a * (1.0 - s) + b * (s * (1.0 - r2)) + c * (s * r2)
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The square [0, 1]² at height z, two triangles.
    fn plate(z: f64) -> Mesh {
        Mesh {
            positions: vec![
                DVec3::new(0.0, 0.0, z),
                DVec3::new(1.0, 0.0, z),
                DVec3::new(1.0, 1.0, z),
                DVec3::new(0.0, 1.0, z),
            ],
            triangles: vec![[0, 1, 2], [0, 2, 3]],
        }
    }

    #[test]
    fn samples_cover_the_area_evenly() {
        let points = sample(&plate(0.0), 10_000).unwrap();
        // Each quarter of the square holds a quarter of the points, within 1 %.
        let quarter = points.iter().filter(|p| p.x < 0.5 && p.y < 0.5).count();
        assert!((quarter as f64 - 2500.0).abs() < 25.0, "{quarter}");
        let mean = points.iter().copied().sum::<DVec3>() / 10_000.0;
        assert!((mean - DVec3::new(0.5, 0.5, 0.0)).length() < 1e-3, "{mean}");
        assert!(sample(&Mesh::default(), 5).is_err());
    }

    #[test]
    fn a_plate_lifted_by_h_is_h_away_both_ways() {
        let h = 0.03;
        let lifted = Surface::Mesh(crate::geometry::import::Imported {
            mesh: plate(h),
            warnings: Vec::new(),
        });
        let s = score(&lifted, &plate(0.0), 2000, 0.05).unwrap();
        assert!((s.chamfer_l1() - h).abs() < 1e-15);
        assert!((s.chamfer_l2() - 2.0 * h * h).abs() < 1e-15);
        assert_eq!((s.precision, s.recall, s.fscore()), (1.0, 1.0, 1.0));
        let s = score(&lifted, &plate(0.0), 2000, 0.02).unwrap();
        assert_eq!(s.fscore(), 0.0);
    }

    /// Points so far away that a distance or its square overflows: a refusal that says why,
    /// not an infinite Chamfer distance (the import refuses such coordinates first; this holds
    /// for any surface handed over).
    #[test]
    fn a_surface_too_far_away_is_refused_not_infinite() {
        for (z, apart) in [(1e154, "up to 1e154 m"), (1e300, "more than 1e154 m")] {
            let far = Surface::Points(vec![DVec3::new(0.5, 0.5, z)]);
            let e = score(&far, &plate(0.0), 100, 0.01).unwrap_err().to_string();
            assert!(
                e.contains("Chamfer distance not defined") && e.contains(apart),
                "{e}"
            );
        }
    }
}
