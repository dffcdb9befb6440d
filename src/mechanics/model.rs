//! Choosing and running the theory a beam needs, and deriving its labels.
//!
//! Both linear theories are cheap, so both are solved: their difference is the estimated
//! error of Euler–Bernoulli, and Timoshenko is used where that error exceeds the tolerance
//! (unless the recipe pins a theory). Geometric nonlinearity is estimated from the rotation
//! (docs/mechanics.md §6.5) and, for axially restrained beams, from the membrane tension
//! (§5.4); both are reported. Loads given as a target deflection only fix the shape, and the
//! physical load is derived from it. Whatever theory ran, the result is checked against the
//! range that theory can represent (§5.3) before anything is built from it.

use super::elastica::Elastica;
use super::linear::{LinearBeam, Load};
use super::membrane::TensionBeam;
use super::restrained::{check_axial, linear_membrane, modal_membrane, von_karman};
use super::{Axial, ModeShape, SectionProperties, Support, range};
use serde::Serialize;

/// Which beam theory computes the deflected axis.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum Theory {
    /// Chosen by estimated error: Euler–Bernoulli, or Timoshenko where shear deformation changes
    /// the deflection by more than `model_tolerance`; the elastica where geometric nonlinearity
    /// exceeds it and the elastica applies.
    #[default]
    Auto,
    /// Linear Euler–Bernoulli theory: sections stay normal to the axis, no shear deformation; small
    /// deflections.
    EulerBernoulli,
    /// Linear Timoshenko theory: adds shear deformation through κGA (G = E / (2 (1 + ν))), which
    /// matters for short, deep beams.
    Timoshenko,
    /// Large-deflection (geometrically exact) inextensible Euler–Bernoulli rod: a cantilever
    /// under one point load, or a simply supported beam under one point load at mid-span.
    Elastica,
    /// Geometrically nonlinear beam with axially restrained ends (von Kármán): EI w'''' − N w''
    /// = q with the membrane tension N = (EA/2L)∫w′² the stretched axis carries; moderate
    /// rotations, no shear deformation. Chosen by `auto` where the membrane error exceeds both
    /// `model_tolerance` and the shear error leaving shear out would make.
    VonKarman,
}

impl Theory {
    /// The name a recipe uses for the theory.
    pub fn name(self) -> &'static str {
        match self {
            Theory::Auto => "auto",
            Theory::EulerBernoulli => "euler_bernoulli",
            Theory::Timoshenko => "timoshenko",
            Theory::Elastica => "elastica",
            Theory::VonKarman => "von_karman",
        }
    }
}

/// What the loads' magnitudes mean.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, schemars::JsonSchema)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Target {
    /// Loads are physical (N, N/m, N·m).
    Physical,
    /// Loads give the shape only; they are scaled so the largest deflection is `deflection`.
    Peak {
        /// The largest deflection wanted, metres, signed (positive downward).
        deflection: f64,
    },
    /// Loads are scaled so the deflection at `at` is `deflection`.
    At {
        /// Where the deflection is prescribed: distance along the axis from x = 0, metres.
        at: f64,
        /// The deflection wanted there, metres, signed (positive downward).
        deflection: f64,
    },
}

/// A beam as the mechanics sees it: supports, span, loads and material, in the beam's own frame
/// (axis along x from 0 to L, deflection positive downward).
#[derive(Clone, Debug)]
pub struct BeamProblem {
    /// How the ends are supported.
    pub support: Support,
    /// Span L, metres.
    pub length: f64,
    /// Loads on the span (N, N/m, N·m, or relative when `target` scales them).
    pub loads: Vec<Load>,
    /// What the load magnitudes mean.
    pub target: Target,
    /// Properties of the cross-section.
    pub section: SectionProperties,
    /// Young's modulus E, Pa.
    pub elastic_modulus: f64,
    /// Poisson's ratio ν.
    pub poisson: f64,
    /// Yield strength f_y, Pa.
    pub yield_strength: f64,
    /// The theory asked for.
    pub theory: Theory,
    /// Largest acceptable model error, as a fraction of the peak deflection.
    pub tolerance: f64,
    /// A vibration snapshot instead of static loads: (mode number, amplitude in metres).
    pub vibration: Vec<(u32, f64)>,
    /// Whether the supports hold the axis along its length.
    pub axial: Axial,
}

/// Labels written next to each sample.
#[derive(Clone, Debug, PartialEq, Serialize, schemars::JsonSchema)]
pub struct Labels {
    /// The theory that produced the shape (never "auto"; a vibration snapshot reports
    /// "euler_bernoulli").
    pub theory: Theory,
    /// Estimated model error as a fraction of the peak deflection: the largest of the shear
    /// error (if Euler–Bernoulli, the elastica or von Kármán ran), the geometric-nonlinearity
    /// error (unless the elastica ran) and the membrane error (if linear theory ran on an
    /// axially restrained beam).
    pub estimated_error: f64,
    /// Estimated relative error of Euler–Bernoulli from neglecting shear deformation, as a fraction
    /// of the peak deflection; 0 when Timoshenko ran.
    pub shear_error: f64,
    /// Estimated relative error of linear theory from geometric nonlinearity, k (δ/L)² with
    /// k = 1.03 for a cantilever and 4.1 otherwise; 0 when the elastica ran.
    pub nonlinearity_error: f64,
    /// How the supports held the axis: "restrained" (both ends held, the axis stretches and
    /// carries `membrane_force`) or "free" (one end slides, the axis keeps its length).
    pub axial: Axial,
    /// Estimated relative error of linear theory from ignoring the membrane tension of an
    /// axially restrained beam, as a fraction of the peak deflection (exact to first order in
    /// the tension; the energy ratio N ∫v′² / (EI ∫v″²) for a vibration snapshot); 0 when von
    /// Kármán ran or the axis is free.
    pub membrane_error: f64,
    /// Axial tension N, newtons: (EA/2L)∫v′² of the deflected axis when the axis is restrained
    /// (the value von Kármán solved for, when it ran); 0 when the axis is free.
    pub membrane_force: f64,
    /// Membrane stress N / A, Pa.
    pub membrane_stress: f64,
    /// The deflection of largest magnitude, metres, signed (positive downward).
    pub max_deflection: f64,
    /// Where it occurs: distance along the axis from x = 0, metres.
    pub max_deflection_at: f64,
    /// The physical loads that produce this shape.
    pub loads: Vec<Load>,
    /// The bending moment of largest magnitude, N·m, signed (sagging positive).
    pub max_moment: f64,
    /// Where it occurs: distance along the axis from x = 0, metres.
    pub max_moment_at: f64,
    /// Largest bending stress σ = |M| c / I at the extreme fibre, Pa.
    pub max_bending_stress: f64,
    /// The beam's yield strength f_y, Pa, against which `physically_plausible` is judged.
    pub yield_strength: f64,
    /// Whether an elastic beam of this material could carry the loads (bending plus membrane
    /// stress at most f_y); otherwise the deflection is a visual exaggeration.
    pub physically_plausible: bool,
    /// For a vibration snapshot: each mode's number, β_nL and amplitude (metres); empty
    /// otherwise.
    pub modes: Vec<ModeLabel>,
    /// When the elastica ran: the relative error linear theory would have made in the peak
    /// deflection under the same load (why it was not used).
    pub linear_theory_error: Option<f64>,
}

/// One mode of a vibration snapshot.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, schemars::JsonSchema)]
pub struct ModeLabel {
    /// Mode number n, from 1 (the fundamental).
    pub mode: u32,
    /// Its eigenvalue β_nL for these supports (ω_n = (β_nL)² √(EI / (ρA L⁴))).
    pub beta_l: f64,
    /// Its amplitude, metres: the peak of its contribution, the mode shape being normalised to a
    /// peak of 1 and positive near x = 0.
    pub amplitude: f64,
}

impl Labels {
    /// Labels from the peaks; stress σ = |M| c / I and plausibility follow. Errors, loads and
    /// modes start empty for the caller to fill.
    pub(super) fn new(
        p: &BeamProblem,
        theory: Theory,
        (max_deflection, max_deflection_at): (f64, f64),
        (max_moment, max_moment_at): (f64, f64),
    ) -> Labels {
        let max_bending_stress =
            max_moment.abs() * p.section.extreme_fibre / p.section.second_moment;
        Labels {
            theory,
            estimated_error: 0.0,
            shear_error: 0.0,
            nonlinearity_error: 0.0,
            axial: p.axial,
            membrane_error: 0.0,
            membrane_force: 0.0,
            membrane_stress: 0.0,
            max_deflection,
            max_deflection_at,
            loads: Vec::new(),
            max_moment,
            max_moment_at,
            max_bending_stress,
            yield_strength: p.yield_strength,
            physically_plausible: max_bending_stress <= p.yield_strength,
            modes: Vec::new(),
            linear_theory_error: None,
        }
    }

    /// Records the membrane tension of a restrained axis: its stress adds to the bending stress
    /// in the plausibility check (σ_b + N/A ≤ f_y).
    pub(super) fn set_membrane(&mut self, p: &BeamProblem, force: f64) {
        self.membrane_force = force;
        self.membrane_stress = force / p.section.area;
        self.physically_plausible =
            self.max_bending_stress + self.membrane_stress.abs() <= self.yield_strength;
    }
}

/// What the axis follows: a static linear solution, or a sum of mode shapes.
#[derive(Clone, Debug)]
pub(super) enum Axis {
    Static {
        beam: LinearBeam,
        scale: f64,
    },
    Modal {
        modes: Vec<(ModeShape, f64)>,
        length: f64,
    },
    /// `sign` −1 mirrors an upward load. With `mirrored`, the rod is half of a simply
    /// supported beam with a centre load: clamped (by symmetry) at mid-span, its free end on
    /// the support, mirrored onto the other half.
    Elastica {
        rod: Elastica,
        sign: f64,
        mirrored: Option<f64>,
    },
    /// The von Kármán solution: a tension beam at its solved tension, scaled like `Static`.
    Tension {
        beam: TensionBeam,
        scale: f64,
    },
    /// A frame of a beam in motion: a static solution plus a sum of mode shapes.
    Superposed {
        base: Box<Axis>,
        modes: Vec<(ModeShape, f64)>,
        length: f64,
    },
}

/// The solved beam: deflection of its axis in metres, and its labels.
#[derive(Clone, Debug)]
pub struct Deformation {
    pub(super) axis: Axis,
    /// What the solution found, for the dataset's records.
    pub labels: Labels,
}

impl Axis {
    /// The deflected axis at x, in metres and radians-as-slopes.
    fn at(&self, x: f64) -> super::AxisPoint {
        match self {
            Axis::Static { beam, scale } => {
                let s = beam.at(x);
                super::AxisPoint {
                    v: scale * s.v,
                    slope: scale * s.slope,
                    rotation: scale * s.rotation,
                    axial: None,
                }
            }
            Axis::Tension { beam, scale } => {
                let s = beam.at(x);
                super::AxisPoint {
                    v: scale * s.v,
                    slope: scale * s.slope,
                    rotation: scale * s.slope,
                    axial: None,
                }
            }
            Axis::Modal { modes, length } => {
                let (v, slope) = modal_at(modes, *length, x);
                super::AxisPoint {
                    v,
                    slope,
                    rotation: slope,
                    axial: None,
                }
            }
            Axis::Superposed {
                base,
                modes,
                length,
            } => {
                let (v, slope) = modal_at(modes, *length, x);
                let b = base.at(x);
                super::AxisPoint {
                    v: b.v + v,
                    slope: b.slope + slope,
                    rotation: b.rotation + slope,
                    axial: b.axial,
                }
            }
            Axis::Elastica {
                rod,
                sign,
                mirrored: None,
            } => {
                let c = rod.at(x);
                let tangent = sign * c.theta.tan();
                super::AxisPoint {
                    v: sign * c.v,
                    slope: tangent,
                    rotation: tangent,
                    axial: Some(c.x),
                }
            }
            Axis::Elastica {
                rod,
                sign,
                mirrored: Some(half),
            } => {
                let (tip, c) = (rod.at(*half), rod.at((half - x).abs()));
                let side = if x <= *half { 1.0 } else { -1.0 };
                let tangent = side * sign * c.theta.tan();
                super::AxisPoint {
                    v: sign * (tip.v - c.v),
                    slope: tangent,
                    rotation: tangent,
                    axial: Some(tip.x - side * c.x),
                }
            }
        }
    }
}

/// Deflection and slope of Σ A_n φ_n(x/L) at x.
fn modal_at(modes: &[(ModeShape, f64)], length: f64, x: f64) -> (f64, f64) {
    modes
        .iter()
        .fold((0.0, 0.0), |(v, slope), (mode, amplitude)| {
            let (phi, dphi, _) = mode.at(x / length);
            (v + amplitude * phi, slope + amplitude * dphi / length)
        })
}

/// Stations used to locate extremes (plus every load point).
const SEARCH_POINTS: usize = 512;

impl Deformation {
    /// Solves `p` with the theory it asks for (or the one `auto` picks) and derives the labels.
    /// Fails when a target deflection cannot be reached, when static loads and a vibration snapshot
    /// are mixed, when a theory or axial condition is asked for a case it does not cover, or when
    /// the result lies outside what the theory that made it can represent (docs/mechanics.md
    /// §5.3).
    pub fn solve(p: &BeamProblem) -> Result<Deformation, String> {
        check_axial(p)?;
        if !p.vibration.is_empty() {
            if !p.loads.is_empty() {
                return Err(
                    "a beam takes either static loads or a vibration snapshot, not both".into(),
                );
            }
            let xs = modal_points(p);
            let d = modal(p, &xs);
            range::check(p, &d, &xs)?;
            return Ok(d);
        }
        let xs = search_points(p);
        let d = statics(p, &xs)?;
        range::check(p, &d, &xs)?;
        Ok(d)
    }

    /// The deflected axis at x, in metres and radians-as-slopes.
    pub fn at(&self, x: f64) -> super::AxisPoint {
        self.axis.at(x)
    }

    /// This solution plus a sum of mode shapes Σ A_n φ_n(x/L) (each φ_n normalised to a peak of
    /// 1, as vibration snapshots are): a frame of a beam in motion by the mode-acceleration
    /// method — the static solution of the loads acting at that instant plus the modes' dynamic
    /// part (`dynamics::Response::dynamic_amplitudes`). The peak deflection label is found again
    /// on the sum; the moment and stress labels stay those of the static part. No amplitudes:
    /// the solution unchanged, bit for bit.
    pub fn plus_modes(self, support: Support, length: f64, amplitudes: &[(u32, f64)]) -> Self {
        if amplitudes.is_empty() {
            return self;
        }
        let modes: Vec<(ModeShape, f64)> = amplitudes
            .iter()
            .map(|&(n, a)| (ModeShape::new(support, n), a))
            .collect();
        let highest = amplitudes.iter().map(|m| m.0 as usize).max().unwrap_or(1);
        let points = SEARCH_POINTS.max(32 * highest);
        let xs: Vec<f64> = (0..=points)
            .map(|i| length * i as f64 / points as f64)
            .collect();
        let mut d = Deformation {
            axis: Axis::Superposed {
                base: Box::new(self.axis),
                modes,
                length,
            },
            labels: self.labels,
        };
        let (max, at) = extreme(&xs, length, |x| d.at(x).v);
        (d.labels.max_deflection, d.labels.max_deflection_at) = (max, at);
        d
    }
    /// Largest |dψ/dx| (curvature of the sections' rotation), for tessellation.
    pub fn max_curvature(&self, length: f64) -> f64 {
        let highest_mode = match &self.axis {
            Axis::Modal { modes, .. } | Axis::Superposed { modes, .. } => {
                modes.iter().map(|(m, _)| m.beta_l()).fold(0.0, f64::max) as usize
            }
            Axis::Static { .. } | Axis::Elastica { .. } | Axis::Tension { .. } => 0,
        };
        let n = 256.max(16 * highest_mode);
        let h = length / n as f64;
        let angle = |x: f64| self.at(x).rotation.atan();
        (0..n)
            .map(|i| ((angle((i + 1) as f64 * h) - angle(i as f64 * h)) / h).abs())
            .fold(0.0, f64::max)
    }
}

/// A static solution: linear theory (Euler–Bernoulli or Timoshenko), or where `auto` finds it
/// wrong by more than the tolerance, the elastica (free axis) or von Kármán (restrained axis).
fn statics(p: &BeamProblem, xs: &[f64]) -> Result<Deformation, String> {
    let pair = LinearPair::solve(p, xs)?;
    // The elastica is the inextensible rod on a roller or free end: free axes only.
    let wants_elastica = p.axial == Axial::Free
        && (p.theory == Theory::Elastica
            || (p.theory == Theory::Auto && pair.nonlinearity_error > p.tolerance));
    if wants_elastica && let Some(d) = elastica(p, pair.ei, pair.shear_error)? {
        return Ok(d);
    }
    if p.theory == Theory::VonKarman {
        return von_karman(p, xs, pair.shear_error);
    }
    linear(p, xs, pair)
}

/// Both linear theories under the recipe's loads, each scaled to its target, and what their
/// difference says about Euler–Bernoulli's error.
struct LinearPair {
    eb: LinearBeam,
    tim: LinearBeam,
    /// Load factors that make each reach the target (1 for physical loads).
    f_eb: f64,
    f_t: f64,
    /// EI and EI/(κGA), m².
    ei: f64,
    flexibility: f64,
    shear_error: f64,
    nonlinearity_error: f64,
}

impl LinearPair {
    fn solve(p: &BeamProblem, xs: &[f64]) -> Result<LinearPair, String> {
        let ei = p.elastic_modulus * p.section.second_moment;
        let shear_modulus = p.elastic_modulus / (2.0 * (1.0 + p.poisson));
        let flexibility = ei / (p.section.shear_coefficient * shear_modulus * p.section.area);
        let eb = LinearBeam::solve(p.support, p.length, &p.loads, 0.0);
        let tim = LinearBeam::solve(p.support, p.length, &p.loads, flexibility);
        let factor = |beam: &LinearBeam| -> Result<f64, String> {
            match p.target {
                Target::Physical => Ok(1.0),
                Target::Peak { deflection } => {
                    let (peak, _) = extreme(xs, p.length, |x| beam.at(x).v);
                    reach(deflection, peak, beam.natural_deflection(), None).map(|f| f * ei)
                }
                Target::At { at, deflection } => reach(
                    deflection,
                    beam.at(at).v,
                    beam.natural_deflection(),
                    Some(at),
                )
                .map(|f| f * ei),
            }
        };
        let (f_eb, f_t) = (factor(&eb)?, factor(&tim)?);
        let (peak_t, _) = extreme(xs, p.length, |x| f_t * tim.at(x).v / ei);
        let shear_error = xs
            .iter()
            .map(|&x| (f_eb * eb.at(x).v - f_t * tim.at(x).v).abs() / ei)
            .fold(0.0, f64::max)
            / peak_t.abs().max(f64::MIN_POSITIVE);
        let nonlinearity_error = nonlinearity(p.support) * (peak_t / p.length).powi(2);
        Ok(LinearPair {
            eb,
            tim,
            f_eb,
            f_t,
            ei,
            flexibility,
            shear_error,
            nonlinearity_error,
        })
    }
}

/// The linear solution `auto` (or the recipe) picks, with its labels; on a restrained axis,
/// von Kármán instead where the membrane tension changes the peak by more than the tolerance
/// (and by more than shear deformation, which von Kármán leaves out).
fn linear(p: &BeamProblem, xs: &[f64], pair: LinearPair) -> Result<Deformation, String> {
    let LinearPair {
        eb,
        tim,
        f_eb,
        f_t,
        ei,
        flexibility,
        shear_error,
        nonlinearity_error,
    } = pair;
    let theory = match p.theory {
        Theory::Auto if shear_error > p.tolerance => Theory::Timoshenko,
        Theory::Auto => Theory::EulerBernoulli,
        pinned => pinned,
    };
    let (beam, load_factor, beam_flexibility) = if theory == Theory::Timoshenko {
        (tim, f_t, flexibility)
    } else {
        (eb, f_eb, 0.0)
    };
    let estimated_error = if theory == Theory::Timoshenko {
        nonlinearity_error
    } else {
        shear_error.max(nonlinearity_error)
    };
    let scale = load_factor / ei;
    let (max_deflection, max_deflection_at) = extreme(xs, p.length, |x| scale * beam.at(x).v);
    let membrane = (p.axial == Axial::Restrained).then(|| {
        let peak = (max_deflection, max_deflection_at);
        linear_membrane(p, &beam, scale, beam_flexibility, peak)
    });
    // Von Kármán leaves shear deformation out: `auto` takes it where the membrane error is too
    // large and larger than the shear error it would make instead.
    if let Some((_, membrane_error)) = membrane
        && p.theory == Theory::Auto
        && membrane_error > p.tolerance
        && membrane_error > shear_error
    {
        return von_karman(p, xs, shear_error);
    }
    let (max_moment, max_moment_at) = extreme(xs, p.length, |x| load_factor * beam.at(x).moment);
    let mut labels = Labels::new(
        p,
        theory,
        (max_deflection, max_deflection_at),
        (max_moment, max_moment_at),
    );
    labels.estimated_error = estimated_error;
    labels.shear_error = if theory == Theory::Timoshenko {
        0.0
    } else {
        shear_error
    };
    labels.nonlinearity_error = nonlinearity_error;
    labels.loads = p.loads.iter().map(|l| scaled(*l, load_factor)).collect();
    if let Some((force, membrane_error)) = membrane {
        labels.membrane_error = membrane_error;
        labels.estimated_error = labels.estimated_error.max(membrane_error);
        labels.set_membrane(p, force);
    }
    Ok(Deformation {
        axis: Axis::Static { beam, scale },
        labels,
    })
}

/// The cantilever elastica for one point load, if the problem is one (None: not applicable
/// under `auto`, so linear theory runs and reports its nonlinearity error).
fn elastica(p: &BeamProblem, ei: f64, shear_error: f64) -> Result<Option<Deformation>, String> {
    let l = p.length;
    // (rod length, load position on the rod, share of the load the rod carries, half span)
    let case = match (p.support, p.loads.as_slice()) {
        (Support::Cantilever, [Load::Point { at, force }]) if *at > 0.0 => {
            Some((l, *at, *force, None))
        }
        (Support::SimplySupported, [Load::Point { at, force }])
            if (at - 0.5 * l).abs() <= 1e-12 * l =>
        {
            Some((0.5 * l, 0.5 * l, 0.5 * force, Some(0.5 * l)))
        }
        _ => None,
    };
    let Some((rod_length, a, force, mirrored)) = case else {
        return if p.theory == Theory::Elastica {
            Err("theory \"elastica\" needs a cantilever with one point load, or a simply supported beam with one centre load".into())
        } else {
            Ok(None)
        };
    };
    let peak_at = mirrored.unwrap_or(l);
    let (rod, sign) = match p.target {
        Target::Physical => (
            Elastica::from_load_parameter(rod_length, a, force.abs() * a * a / ei),
            force.signum(),
        ),
        Target::Peak { deflection } => (
            Elastica::from_tip_deflection(rod_length, a, deflection.abs())?,
            deflection.signum(),
        ),
        Target::At { at, deflection } if (at - peak_at).abs() <= 1e-12 * l => (
            Elastica::from_tip_deflection(rod_length, a, deflection.abs())?,
            deflection.signum(),
        ),
        Target::At { .. } if p.theory == Theory::Elastica => {
            return Err(format!(
                "theory \"elastica\" takes a target deflection at x = {peak_at} m"
            ));
        }
        Target::At { .. } => return Ok(None),
    };
    let sign = if sign == 0.0 { 1.0 } else { sign };
    let rod_load = sign * rod.alpha() * ei / (a * a);
    let tip = rod.at(rod_length);
    // The rod's clamp moment: its load times the deformed lever arm. For the cantilever it is
    // hogging at the clamp; for the simply supported beam it is the sagging moment at mid-span.
    let (load, max_moment, max_moment_at) = match mirrored {
        None => (rod_load, -rod_load * rod.at(a).x, 0.0),
        Some(half) => (2.0 * rod_load, rod_load * tip.x, half),
    };
    let mut labels = Labels::new(
        p,
        Theory::Elastica,
        (sign * tip.v, peak_at),
        (max_moment, max_moment_at),
    );
    labels.estimated_error = shear_error;
    labels.shear_error = shear_error;
    labels.loads = vec![Load::Point {
        at: mirrored.unwrap_or(a),
        force: load,
    }];
    labels.linear_theory_error = Some(rod.linear_error());
    Ok(Some(Deformation {
        axis: Axis::Elastica {
            rod,
            sign,
            mirrored,
        },
        labels,
    }))
}

/// Stations where a vibration snapshot is searched for its extremes: 32 per mode number.
fn modal_points(p: &BeamProblem) -> Vec<f64> {
    let points = SEARCH_POINTS.max(32 * highest_mode(p));
    (0..=points)
        .map(|i| p.length * i as f64 / points as f64)
        .collect()
}

pub(super) fn highest_mode(p: &BeamProblem) -> usize {
    p.vibration.iter().map(|m| m.0 as usize).max().unwrap_or(1)
}

/// A snapshot of free vibration: v(x) = Σ A_n φ_n(x/L), each φ_n normalised to max |φ_n| = 1.
fn modal(p: &BeamProblem, xs: &[f64]) -> Deformation {
    let modes: Vec<(ModeShape, f64)> = p
        .vibration
        .iter()
        .map(|&(n, a)| (ModeShape::new(p.support, n), a))
        .collect();
    let length = p.length;
    let curvature = |x: f64| {
        modes
            .iter()
            .map(|(m, a)| a * m.at(x / length).2)
            .sum::<f64>()
            / (length * length)
    };
    let deflection = |x: f64| {
        modes
            .iter()
            .map(|(m, a)| a * m.at(x / length).0)
            .sum::<f64>()
    };
    let (max_deflection, max_deflection_at) = extreme(xs, length, deflection);
    let (max_curvature, max_moment_at) = extreme(xs, length, curvature);
    let ei = p.elastic_modulus * p.section.second_moment;
    // Shear deflection relative to bending for a half-wave of length L/n: (nπ)² EI/(κGA L²).
    let shear_modulus = p.elastic_modulus / (2.0 * (1.0 + p.poisson));
    let flexibility = ei / (p.section.shear_coefficient * shear_modulus * p.section.area);
    let highest = modes.iter().map(|(m, _)| m.beta_l()).fold(0.0, f64::max);
    let shear_error = highest * highest * flexibility / (length * length);
    let nonlinearity_error = nonlinearity(p.support) * (max_deflection / length).powi(2);
    let mut labels = Labels::new(
        p,
        Theory::EulerBernoulli,
        (max_deflection, max_deflection_at),
        (-ei * max_curvature, max_moment_at),
    );
    labels.estimated_error = shear_error.max(nonlinearity_error);
    labels.shear_error = shear_error;
    labels.nonlinearity_error = nonlinearity_error;
    labels.modes = modes
        .iter()
        .zip(&p.vibration)
        .map(|((m, a), &(n, _))| ModeLabel {
            mode: n,
            beta_l: m.beta_l(),
            amplitude: *a,
        })
        .collect();
    if p.axial == Axial::Restrained {
        let slope = |x: f64| -> f64 {
            modes
                .iter()
                .map(|(m, a)| a * m.at(x / length).1)
                .sum::<f64>()
                / length
        };
        let (force, membrane_error) = modal_membrane(p, &slope, &curvature);
        labels.membrane_error = membrane_error;
        labels.estimated_error = labels.estimated_error.max(membrane_error);
        labels.set_membrane(p, force);
    }
    Deformation {
        axis: Axis::Modal { modes, length },
        labels,
    }
}

/// Linear theory's relative tip error ≈ k (δ/L)²: 1.03 for a cantilever, 4.1 for beams held at
/// both ends (half-span analogue, docs/mechanics.md §6.5).
pub(super) fn nonlinearity(support: Support) -> f64 {
    if support == Support::Cantilever {
        1.03
    } else {
        4.1
    }
}

/// Load factor per unit EI that turns `unit` (the unit loads' deflection at `at`, or their
/// peak when None) into `target`.
pub(super) fn reach(target: f64, unit: f64, natural: f64, at: Option<f64>) -> Result<f64, String> {
    if !(unit.abs() > 1e-14 * natural) {
        return Err(match at {
            None => format!(
                "target deflection {target} m cannot be reached: the loads do not deflect the beam anywhere (is every load on a support?)"
            ),
            Some(x) => format!(
                "target deflection {target} m at x = {x} m cannot be reached: the loads do not deflect the beam there (is x = {x} m a support, or every load on one?)"
            ),
        });
    }
    Ok(target / unit)
}

pub(super) fn scaled(load: Load, f: f64) -> Load {
    match load {
        Load::Point { at, force } => Load::Point {
            at,
            force: force * f,
        },
        Load::Distributed {
            from,
            to,
            intensity,
        } => Load::Distributed {
            from,
            to,
            intensity: intensity * f,
        },
        Load::EndMoments { start, end } => Load::EndMoments {
            start: start * f,
            end: end * f,
        },
    }
}

fn search_points(p: &BeamProblem) -> Vec<f64> {
    let mut xs: Vec<f64> = (0..=SEARCH_POINTS)
        .map(|i| p.length * i as f64 / SEARCH_POINTS as f64)
        .collect();
    for load in &p.loads {
        if let Load::Point { at, .. } = load {
            xs.push(*at);
        }
    }
    xs
}

/// The value of largest magnitude (signed) and where, refined by golden-section search around
/// the best sample. `xs` starts with a uniform grid over [0, length].
pub(super) fn extreme(xs: &[f64], length: f64, f: impl Fn(f64) -> f64) -> (f64, f64) {
    let (mut best_x, mut best) = (xs[0], f(xs[0]));
    for &x in xs {
        let y = f(x);
        if y.abs() > best.abs() {
            (best_x, best) = (x, y);
        }
    }
    let step = xs[1] - xs[0];
    let (mut a, mut b) = ((best_x - step).max(0.0), (best_x + step).min(length));
    let g = 0.5 * (5f64.sqrt() - 1.0);
    for _ in 0..60 {
        let (c, d) = (b - g * (b - a), a + g * (b - a));
        if f(c).abs() >= f(d).abs() {
            b = d
        } else {
            a = c
        }
    }
    let x = 0.5 * (a + b);
    if f(x).abs() > best.abs() {
        (f(x), x)
    } else {
        (best, best_x)
    }
}

/// A steel (S355) beam of rectangular section for the tests: theory `auto`, tolerance 1 %,
/// the support's own axial condition.
#[cfg(test)]
pub(super) fn steel_rectangle(
    support: Support,
    length: f64,
    (width, height): (f64, f64),
    loads: Vec<Load>,
    target: Target,
) -> BeamProblem {
    BeamProblem {
        support,
        length,
        loads,
        target,
        section: super::Section::Rectangle { width, height }.properties(super::STEEL_NU),
        elastic_modulus: super::STEEL_E,
        poisson: super::STEEL_NU,
        yield_strength: super::STEEL_FY,
        theory: Theory::Auto,
        tolerance: 0.01,
        vibration: Vec::new(),
        axial: Axial::of(support),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn problem(support: Support, l_over_h: f64, loads: Vec<Load>, target: Target) -> BeamProblem {
        let h = 0.5;
        steel_rectangle(support, l_over_h * h, (0.3, h), loads, target)
    }

    #[test]
    fn euler_bernoulli_error_by_slenderness_matches_the_published_table() {
        // docs/mechanics.md §4.4 (Cowper κ, ν = 0.3): (δ_EB − δ_T)/δ_T for SS centre load is
        // −25.4 % at L/h = 3, −2.97 % at 10, −0.03 % at 100; cantilever tip −7.83 %, −0.76 %, −0.01 %.
        for (support, at, table) in [
            (
                Support::SimplySupported,
                0.5,
                [(3.0, -25.4), (10.0, -2.97), (100.0, -0.03)],
            ),
            (
                Support::Cantilever,
                1.0,
                [(3.0, -7.83), (10.0, -0.76), (100.0, -0.01)],
            ),
        ] {
            for (lh, percent) in table {
                let mut p = problem(support, lh, vec![], Target::Physical);
                p.loads = vec![Load::Point {
                    at: at * p.length,
                    force: 1e4,
                }];
                p.theory = Theory::EulerBernoulli;
                let eb = Deformation::solve(&p).unwrap().labels.max_deflection;
                p.theory = Theory::Timoshenko;
                let t = Deformation::solve(&p).unwrap().labels.max_deflection;
                let got = 100.0 * (eb - t) / t;
                assert!(
                    (got - percent).abs() < 0.006 + 0.002 * percent.abs(),
                    "{support:?} L/h={lh}: {got:.3} % vs {percent} %"
                );
            }
        }
    }

    #[test]
    fn auto_picks_timoshenko_for_stocky_beams_only() {
        let target = Target::Peak { deflection: 0.001 };
        let load = |p: &BeamProblem| {
            vec![Load::Point {
                at: 0.5 * p.length,
                force: 1.0,
            }]
        };
        let mut stocky = problem(Support::SimplySupported, 3.0, vec![], target);
        stocky.loads = load(&stocky);
        let d = Deformation::solve(&stocky).unwrap();
        assert_eq!(d.labels.theory, Theory::Timoshenko);
        assert!((d.labels.max_deflection - 0.001).abs() < 1e-15);
        let mut slender = problem(Support::SimplySupported, 200.0, vec![], target);
        slender.loads = load(&slender);
        let d = Deformation::solve(&slender).unwrap();
        assert_eq!(d.labels.theory, Theory::EulerBernoulli);
        assert!(d.labels.estimated_error < 0.01);
        // Shape difference at L/h = 3 for a target peak: 4.88 % of δ (docs/mechanics.md §4.5).
        assert!(
            (Deformation::solve(&{
                let mut p = stocky.clone();
                p.theory = Theory::EulerBernoulli;
                p
            })
            .unwrap()
            .labels
            .shear_error
                - 0.0488)
                .abs()
                < 0.001
        );
    }

    #[test]
    fn targets_and_derived_loads() {
        // SS centre target δ: P = 48 EI δ/L³, M = PL/4, σ = M c/I.
        let mut p = problem(
            Support::SimplySupported,
            40.0,
            vec![],
            Target::Peak { deflection: 1.0 },
        );
        p.loads = vec![Load::Point {
            at: 10.0,
            force: 1.0,
        }];
        p.theory = Theory::EulerBernoulli;
        let d = Deformation::solve(&p).unwrap();
        let ei = 210e9 * p.section.second_moment;
        let want = 48.0 * ei * 1.0 / 20f64.powi(3);
        let Load::Point { force, .. } = d.labels.loads[0] else {
            panic!()
        };
        assert!((force / want - 1.0).abs() < 1e-12);
        assert!((d.labels.max_moment / (want * 5.0) - 1.0).abs() < 1e-9);
        assert!((d.labels.max_deflection_at - 10.0).abs() < 1e-6);
        assert!(
            !d.labels.physically_plausible,
            "0.05 L at L/h = 40 exceeds yield (docs/mechanics.md §3.3)"
        );
        // Target at a point.
        p.target = Target::At {
            at: 5.0,
            deflection: 0.01,
        };
        assert!((Deformation::solve(&p).unwrap().at(5.0).v - 0.01).abs() < 1e-15);
    }

    #[test]
    fn auto_switches_to_the_elastica_for_large_cantilever_deflections() {
        // Bisshopp–Drucker, α = PL²/EI = 1: δ/L = 0.30172, shortening u/L = 0.05643
        // (docs/mechanics.md §6.4).
        let mut p = problem(Support::Cantilever, 40.0, vec![], Target::Physical);
        let ei = 210e9 * p.section.second_moment;
        p.loads = vec![Load::Point {
            at: p.length,
            force: ei / (p.length * p.length),
        }];
        let d = Deformation::solve(&p).unwrap();
        assert_eq!(d.labels.theory, Theory::Elastica);
        assert!((d.labels.max_deflection / p.length - 0.30172).abs() < 1e-5);
        assert!((d.at(p.length).axial.unwrap() / p.length - (1.0 - 0.05643)).abs() < 1e-5);
        // Moment at the clamp uses the deformed lever arm (1 − u/L)·L.
        assert!(
            (d.labels.max_moment / (-(ei / (p.length * p.length)) * p.length * (1.0 - 0.05643))
                - 1.0)
                .abs()
                < 1e-4
        );
        // Linear theory would have said α/3 = 0.3333: +10.5 % (docs/mechanics.md §6.4).
        assert!((d.labels.linear_theory_error.unwrap() - 0.105).abs() < 0.001);
        // Small deflections stay linear; an upward target mirrors.
        p.loads = vec![Load::Point {
            at: p.length,
            force: 1.0,
        }];
        p.target = Target::Peak {
            deflection: 0.001 * p.length,
        };
        assert_eq!(
            Deformation::solve(&p).unwrap().labels.theory,
            Theory::EulerBernoulli
        );
        p.target = Target::Peak {
            deflection: -0.4 * p.length,
        };
        let d = Deformation::solve(&p).unwrap();
        assert_eq!(d.labels.theory, Theory::Elastica);
        assert!((d.at(p.length).v + 0.4 * p.length).abs() < 1e-9 * p.length);
        // A simply supported centre load is two half-span cantilevers with P/2: α_half = PL²/(8EI).
        p.support = Support::SimplySupported;
        p.loads = vec![Load::Point {
            at: 0.5 * p.length,
            force: 8.0 * ei / (p.length * p.length),
        }];
        p.target = Target::Physical;
        let d = Deformation::solve(&p).unwrap();
        assert_eq!(d.labels.theory, Theory::Elastica);
        let half = 0.5 * p.length;
        assert!((d.labels.max_deflection / half - 0.30172).abs() < 1e-5);
        assert!(
            (d.at(p.length).axial.unwrap() - p.length * (1.0 - 0.05643)).abs() < 1e-5 * p.length,
            "roller moves in by 2u"
        );
        assert!(d.at(0.0).v.abs() < 1e-12 && d.at(p.length).v.abs() < 1e-12);
        assert!(
            (d.at(0.3 * p.length).v - d.at(0.7 * p.length).v).abs() < 1e-12 * p.length,
            "symmetric"
        );
        // Pinned, on a case it cannot take: a clear error.
        p.loads = vec![Load::Point {
            at: 0.3 * p.length,
            force: 1.0,
        }];
        p.theory = Theory::Elastica;
        assert!(Deformation::solve(&p).unwrap_err().contains("elastica"));
    }

    #[test]
    fn vibration_snapshots_superpose_normalised_modes() {
        // Mode 1 of a simply supported beam is sin(πx/L); the stress is E c A (π/L)².
        let mut p = problem(Support::SimplySupported, 20.0, vec![], Target::Physical);
        p.vibration = vec![(1, 0.02)];
        let d = Deformation::solve(&p).unwrap();
        assert!((d.at(2.5).v - 0.02 * (std::f64::consts::PI * 0.25).sin()).abs() < 1e-15);
        let want = 210e9 * 0.25 * 0.02 * (std::f64::consts::PI / 10.0).powi(2);
        assert!((d.labels.max_bending_stress / want - 1.0).abs() < 1e-9);
        // Cantilever mode 100: finite everywhere, peak amplitude as requested, clamp holds.
        p.support = Support::Cantilever;
        p.vibration = vec![(100, 0.001), (2, 0.01)];
        let d = Deformation::solve(&p).unwrap();
        assert!(
            d.at(0.0).v.abs() < 1e-16 && d.at(0.0).slope.abs() < 1e-14,
            "clamp: {:?}",
            d.at(0.0)
        );
        for i in 0..=10_000 {
            let a = d.at(10.0 * f64::from(i) / 10_000.0);
            assert!(a.v.is_finite() && a.slope.is_finite() && a.v.abs() <= 0.011 + 1e-12);
        }
        assert_eq!(d.labels.modes.len(), 2);
        assert!(
            d.labels.shear_error > 0.1,
            "mode 100 on an L/h = 20 beam is far outside Euler–Bernoulli"
        );
        p.loads = vec![Load::Point {
            at: 1.0,
            force: 1.0,
        }];
        assert!(Deformation::solve(&p).is_err());
    }

    #[test]
    fn loads_at_supports() {
        // Physical load on a support: no deflection, no NaN. As a target: a clear error.
        for support in [
            Support::SimplySupported,
            Support::Cantilever,
            Support::FixedFixed,
            Support::ProppedCantilever,
        ] {
            let mut p = problem(
                support,
                20.0,
                vec![Load::Point {
                    at: 0.0,
                    force: 1e5,
                }],
                Target::Physical,
            );
            let d = Deformation::solve(&p).unwrap();
            assert!(
                d.labels.max_deflection.abs() < 1e-15,
                "{support:?}: {}",
                d.labels.max_deflection
            );
            p.target = Target::Peak { deflection: 0.01 };
            assert!(Deformation::solve(&p).unwrap_err().contains("on a support"));
            // Just inside the span (1e-6 L) the load still reaches its target under
            // Euler–Bernoulli next to a pin. Next to a clamp the whole end rotation happens
            // within 1e-6 L (bending strain 50 and more at the extreme fibre), and under
            // Timoshenko the deflection drops in a shear step there (slopes of 10 to 1000): each
            // is refused, naming the quantity (docs/mechanics.md §5.3).
            p.loads = vec![Load::Point {
                at: 1e-6 * p.length,
                force: 1.0,
            }];
            p.theory = Theory::EulerBernoulli;
            match Deformation::solve(&p) {
                Ok(d) => assert!(
                    support == Support::SimplySupported
                        && (d.labels.max_deflection - 0.01).abs() < 1e-9,
                    "{support:?}: {}",
                    d.labels.max_deflection
                ),
                Err(e) => assert!(e.contains("bending strain at the extreme fibre"), "{e}"),
            }
            p.theory = Theory::Timoshenko;
            let e = Deformation::solve(&p).unwrap_err();
            assert!(e.contains("slope of the axis |dv/dx|"), "{support:?}: {e}");
            assert!(e.contains("shear strain next to a load close to a support"));
            p.theory = Theory::Auto;
        }
        // The roller end of a simply supported beam.
        let mut p = problem(
            Support::SimplySupported,
            20.0,
            vec![Load::Point {
                at: 10.0,
                force: 1.0,
            }],
            Target::Peak { deflection: 0.02 },
        );
        p.loads = vec![Load::Point {
            at: p.length,
            force: 1.0,
        }];
        assert!(Deformation::solve(&p).is_err());
    }
}
