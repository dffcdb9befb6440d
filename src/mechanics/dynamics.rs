//! How a uniform Euler–Bernoulli beam moves under loads that change in time: moving axle
//! groups, hammer blows, ramps and steps, and sampled force histories (ambient excitation), by
//! modal superposition with modal damping.
//!
//! Owns: the modal model of a beam (frequencies, modal masses, the mode shapes of `modes`), the
//! integration of each modal coordinate, and the deflection, moment and acceleration at any
//! point and instant. Must not touch: meshes, cameras, files or random streams (a random
//! excitation arrives here as sampled values drawn by the caller).
//!
//! Method (derivation in `docs/mechanics.md` §10):
//! - Each mode n obeys q̈ + 2ζω q̇ + ω² q = f(t), f = Σ F_i(t) φ_n(x_i(t)) / M_n.
//! - Between time nodes f is taken as linear, and the step is the exact solution of that
//!   linear-forcing problem (the idea of Nigam & Jennings 1969): the state [q, q̇, f, ḟ] advances
//!   by the matrix exponential of its 4×4 generator, so there is no stability limit and no
//!   cancellation for small ωh. The only error is the linear interpolation of f, O((ω_f h)²)
//!   for a force varying at ω_f; time nodes include every instant where a force starts, stops
//!   or has a corner, so steps and axles leaving a cantilever's tip are exact.
//! - The deflection is by the mode-acceleration method: the static solution of the loads acting
//!   at that instant plus Σ (q_n − f_n/ω_n²) φ_n. A slowly applied load therefore gives the
//!   static solver's answer whatever the number of modes, and moments converge as fast as
//!   deflections do.

use super::{LinearBeam, Load, ModeShape, Support};
use nalgebra::Matrix4;
use serde::Serialize;
use std::f64::consts::PI;

/// Integration steps per period of the fastest variation of a modal force that frames and
/// sensors use, so they agree: the forces' linear interpolation between steps, the only error,
/// stays below (π/64)²/2 ≈ 0.12 % of their amplitude.
pub const STEPS_PER_PERIOD: u32 = 64;

/// One axle of a vehicle: its distance behind the front axle (m) and its force (N, downward).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, schemars::JsonSchema)]
pub struct Axle {
    /// Distance behind the leading axle, metres (0 for the leading axle).
    pub behind: f64,
    /// Force on the deck, N, positive downward.
    pub force: f64,
}

/// A force history acting on the beam. Times in seconds, positions in metres from x = 0,
/// forces in N (positive downward).
#[derive(Clone, Debug, PartialEq, Serialize, schemars::JsonSchema)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum TimeLoad {
    /// Axles crossing from x = 0 towards x = L at constant speed; each acts while on the span.
    Vehicle {
        /// The axles, leading axle first.
        axles: Vec<Axle>,
        /// Speed, m/s (positive).
        speed: f64,
        /// When the leading axle reaches x = 0.
        enters: f64,
    },
    /// A hammer blow: a half-sine of peak `force`.
    Pulse {
        /// Where it strikes.
        at: f64,
        /// Peak force.
        force: f64,
        /// When it starts.
        start: f64,
        /// How long it lasts (positive).
        duration: f64,
    },
    /// A force growing linearly from 0 to `force`, then held (a step when `rise` is 0).
    Ramp {
        /// Where it acts.
        at: f64,
        /// Final force.
        force: f64,
        /// When it starts to grow.
        start: f64,
        /// How long it takes to reach `force` (0 for a step).
        rise: f64,
    },
    /// A force through sampled values, linear between them and zero outside: a measured or
    /// drawn excitation.
    Sampled {
        /// Where it acts.
        at: f64,
        /// The time of the first value.
        start: f64,
        /// Time between values (positive).
        step: f64,
        /// The force at `start + k·step` (at least two values).
        values: Vec<f64>,
    },
}

impl TimeLoad {
    /// The point forces (position, N) this load applies at time `t`, on the given side of `t`
    /// (the two differ where a force jumps: an axle arriving or leaving, a step).
    pub(crate) fn forces_at(&self, t: f64, side: Side, length: f64, out: &mut Vec<(f64, f64)>) {
        match self {
            TimeLoad::Vehicle {
                axles,
                speed,
                enters,
            } => {
                let front = speed * (t - enters);
                for axle in axles {
                    let x = front - axle.behind;
                    if side.within(x, 0.0, length) {
                        out.push((x, axle.force));
                    }
                }
            }
            &TimeLoad::Pulse {
                at,
                force,
                start,
                duration,
            } => {
                let s = (t - start) / duration;
                if (0.0..=1.0).contains(&s) {
                    out.push((at, force * (PI * s).sin()));
                }
            }
            &TimeLoad::Ramp {
                at,
                force,
                start,
                rise,
            } => {
                if side.within(t, start, f64::INFINITY) {
                    let grown = if rise == 0.0 {
                        1.0
                    } else {
                        ((t - start) / rise).min(1.0)
                    };
                    out.push((at, force * grown));
                }
            }
            TimeLoad::Sampled {
                at,
                start,
                step,
                values,
            } => {
                let s = (t - start) / step;
                let last = values.len().saturating_sub(1) as f64;
                if side.within(s, 0.0, last) {
                    let k = (s.floor().max(0.0) as usize).min(values.len() - 2);
                    let w = s - k as f64;
                    out.push((*at, values[k] * (1.0 - w) + values[k + 1] * w));
                }
            }
        }
    }

    /// Instants where the force jumps or has a corner: time nodes must fall on them.
    pub(crate) fn corners(&self, length: f64, out: &mut Vec<f64>) {
        match self {
            TimeLoad::Vehicle {
                axles,
                speed,
                enters,
            } => {
                for axle in axles {
                    let on = enters + axle.behind / speed;
                    out.extend([on, on + length / speed]);
                }
            }
            TimeLoad::Pulse {
                start, duration, ..
            } => out.extend([*start, start + duration]),
            TimeLoad::Ramp { start, rise, .. } => out.extend([*start, start + rise]),
            TimeLoad::Sampled {
                start,
                step,
                values,
                ..
            } => out.extend((0..values.len()).map(|k| start + k as f64 * step)),
        }
    }

    /// The highest angular frequency at which this load's modal forces vary, rad/s, for a beam
    /// keeping `modes` modes (0 where they are linear between corners).
    pub(crate) fn variation(&self, length: f64, modes: usize) -> f64 {
        match self {
            // An axle at x = ct meets mode n's waves at about nπc/L.
            TimeLoad::Vehicle { speed, .. } => PI * speed * modes as f64 / length,
            TimeLoad::Pulse { duration, .. } => PI / duration,
            TimeLoad::Ramp { .. } | TimeLoad::Sampled { .. } => 0.0,
        }
    }

    /// Every number is finite and the load is well formed; otherwise the parameter and value.
    pub fn check(&self, length: f64) -> Result<(), String> {
        let position = |at: f64| {
            if (0.0..=length).contains(&at) {
                Ok(())
            } else {
                Err(format!(
                    "load position {at} m lies off the span 0 to {length} m"
                ))
            }
        };
        let finite = |name: &str, v: f64| {
            if v.is_finite() {
                Ok(())
            } else {
                Err(format!("{name} must be finite, got {v}"))
            }
        };
        match self {
            TimeLoad::Vehicle {
                axles,
                speed,
                enters,
            } => {
                finite("enters", *enters)?;
                if !(speed.is_finite() && *speed > 0.0) {
                    return Err(format!("speed must be positive, got {speed} m/s"));
                }
                if axles.is_empty() {
                    return Err("a vehicle needs at least one axle".into());
                }
                for a in axles {
                    finite("axle force", a.force)?;
                    if !(a.behind.is_finite() && a.behind >= 0.0) {
                        return Err(format!("axle spacing must be ≥ 0, got {} m", a.behind));
                    }
                }
                Ok(())
            }
            TimeLoad::Pulse {
                at,
                force,
                start,
                duration,
            } => {
                position(*at)?;
                finite("force", *force)?;
                finite("start", *start)?;
                if !(duration.is_finite() && *duration > 0.0) {
                    return Err(format!("pulse duration must be positive, got {duration} s"));
                }
                Ok(())
            }
            TimeLoad::Ramp {
                at,
                force,
                start,
                rise,
            } => {
                position(*at)?;
                finite("force", *force)?;
                finite("start", *start)?;
                if !(rise.is_finite() && *rise >= 0.0) {
                    return Err(format!("ramp rise must be ≥ 0, got {rise} s"));
                }
                Ok(())
            }
            TimeLoad::Sampled {
                at,
                start,
                step,
                values,
            } => {
                position(*at)?;
                finite("start", *start)?;
                if !(step.is_finite() && *step > 0.0) {
                    return Err(format!("sample step must be positive, got {step} s"));
                }
                if values.len() < 2 {
                    return Err(format!(
                        "a sampled force needs at least two values (it is linear between them), got {}",
                        values.len()
                    ));
                }
                values.iter().try_for_each(|&v| finite("sampled force", v))
            }
        }
    }
}

/// Which limit of a force history at an instant: just before it or just after it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Side {
    Before,
    After,
}

impl Side {
    /// Whether a quantity increasing through `x` lies in [lo, hi] on this side of the instant:
    /// just before, the interval is (lo, hi]; just after, [lo, hi).
    pub(crate) fn within(self, x: f64, lo: f64, hi: f64) -> bool {
        match self {
            Side::Before => lo < x && x <= hi,
            Side::After => lo <= x && x < hi,
        }
    }
}

/// One mode of the beam: its shape, angular frequency ω (rad/s) and modal mass (kg).
#[derive(Clone, Debug)]
struct Mode {
    shape: ModeShape,
    omega: f64,
    mass: f64,
}

/// A uniform Euler–Bernoulli beam described by its lowest modes.
#[derive(Clone, Debug)]
pub struct ModalBeam {
    support: Support,
    length: f64,
    ei: f64,
    damping: f64,
    modes: Vec<Mode>,
}

impl ModalBeam {
    /// `mass` is per unit length (kg/m), `damping` the modal damping ratio ζ of every mode
    /// (0 ≤ ζ < 1 for a beam that rings), `modes` how many modes to keep.
    pub fn new(
        support: Support,
        length: f64,
        ei: f64,
        mass: f64,
        damping: f64,
        modes: u32,
    ) -> Result<ModalBeam, String> {
        let positive = |name: &str, v: f64| {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(format!("{name} must be positive, got {v}"))
            }
        };
        positive("length", length)?;
        positive("EI", ei)?;
        positive("mass per length", mass)?;
        if !(damping.is_finite() && (0.0..1.0).contains(&damping)) {
            return Err(format!("damping ratio must be in [0, 1), got {damping}"));
        }
        if modes == 0 {
            return Err("at least one mode is needed".into());
        }
        let modes = (1..=modes)
            .map(|n| {
                let shape = ModeShape::new(support, n);
                let beta = shape.beta_l() / length;
                Mode {
                    omega: beta * beta * (ei / mass).sqrt(),
                    mass: mass * length * mean_square(&shape, n),
                    shape,
                }
            })
            .collect();
        Ok(ModalBeam {
            support,
            length,
            ei,
            damping,
            modes,
        })
    }

    /// The span, m.
    pub fn length(&self) -> f64 {
        self.length
    }

    /// The bending stiffness EI, N·m².
    pub fn ei(&self) -> f64 {
        self.ei
    }

    /// Natural frequencies of the kept modes, Hz.
    pub fn frequencies(&self) -> Vec<f64> {
        self.modes.iter().map(|m| m.omega / (2.0 * PI)).collect()
    }

    /// Integrate from rest at time `from` and return the state at each of `times` (ascending,
    /// none before `from`). `per_period` is the number of steps per period of the fastest
    /// variation of a modal force, which sets the only error, the force's linear interpolation:
    /// about (π/per_period)²/2 of its amplitude at worst.
    pub fn respond(
        &self,
        loads: &[TimeLoad],
        from: f64,
        times: &[f64],
        per_period: u32,
    ) -> Response {
        let mut corners = Vec::new();
        for load in loads {
            load.corners(self.length, &mut corners);
        }
        let forcing = loads
            .iter()
            .map(|l| l.variation(self.length, self.modes.len()))
            .fold(0.0, f64::max);
        let nodes = time_nodes(corners, forcing, from, times, per_period);
        let omegas: Vec<f64> = self.modes.iter().map(|m| m.omega).collect();
        let snapshots = integrate(&omegas, self.damping, from, &nodes, times, |t, side| {
            self.modal_forces(loads, t, side)
        });
        Response { snapshots }
    }

    /// Modal forces f_n = Σ F φ_n(x) / M_n at time t (accelerations of the modal coordinates).
    fn modal_forces(&self, loads: &[TimeLoad], t: f64, side: Side) -> Vec<f64> {
        let forces = self.point_forces(loads, t, side);
        self.modes
            .iter()
            .map(|m| {
                forces
                    .iter()
                    .map(|&(x, f)| f * m.shape.at(x / self.length).0)
                    .sum::<f64>()
                    / m.mass
            })
            .collect()
    }

    fn point_forces(&self, loads: &[TimeLoad], t: f64, side: Side) -> Vec<(f64, f64)> {
        let mut forces = Vec::new();
        for load in loads {
            load.forces_at(t, side, self.length, &mut forces);
        }
        forces
    }

    /// The loads acting just after time t as static span loads (outputs are right-continuous,
    /// like the modal forces stored with them): the static part of the deflection at t.
    pub fn static_loads(&self, loads: &[TimeLoad], t: f64) -> Vec<Load> {
        self.point_forces(loads, t, Side::After)
            .into_iter()
            .map(|(at, force)| Load::Point { at, force })
            .collect()
    }
}

/// Time nodes from `from` to the last output time: every output time and force corner, with
/// steps of at most 2π/(ω_f · per_period) between them for the fastest force variation ω_f
/// (rad/s; 0 where the forces are linear between corners). The modes' own frequencies set no
/// limit: the step is exact for any length, only the force's interpolation needs resolving.
pub(crate) fn time_nodes(
    corners: Vec<f64>,
    forcing: f64,
    from: f64,
    times: &[f64],
    per_period: u32,
) -> Vec<f64> {
    let last = times.last().copied().unwrap_or(from).max(from);
    let h = 2.0 * PI / (forcing * per_period.max(4) as f64);
    let mut fixed: Vec<f64> = times.to_vec();
    fixed.extend(corners);
    fixed.retain(|&t| t > from && t <= last);
    fixed.push(last);
    fixed.sort_by(f64::total_cmp);
    fixed.dedup();
    let mut nodes = Vec::new();
    let mut start = from;
    for &end in &fixed {
        let pieces = ((end - start) / h).ceil().max(1.0);
        nodes.extend((1..pieces as usize).map(|i| start + (end - start) * i as f64 / pieces));
        nodes.push(end);
        start = end;
    }
    nodes
}

/// Modal coordinates q̈ + 2ζω q̇ + ω² q = f(t) of modes of angular frequency `omegas` and
/// damping ratio ζ = `damping`, integrated from rest at `from` through `nodes` (ascending,
/// containing every output time), exact for `forces` linear between nodes; the state at each
/// of `times`. `forces(t, side)` gives every mode's f on that side of t.
pub(crate) fn integrate(
    omegas: &[f64],
    damping: f64,
    from: f64,
    nodes: &[f64],
    times: &[f64],
    forces: impl Fn(f64, Side) -> Vec<f64>,
) -> Vec<Snapshot> {
    let mut state: Vec<[f64; 2]> = vec![[0.0; 2]; omegas.len()];
    let mut force = forces(from, Side::After);
    let mut snapshots = Vec::with_capacity(times.len());
    let mut t = from;
    // Output times at `from` itself see the state at rest, before any step.
    record(&mut snapshots, times, t, &state, &force);
    let mut stepper = Stepper::default();
    for &node in nodes {
        let h = node - t;
        if h > 0.0 {
            let arriving = forces(node, Side::Before);
            for (k, &omega) in omegas.iter().enumerate() {
                let step = stepper.get(omega, damping, h, k);
                state[k] = step.advance(state[k], force[k], arriving[k]);
            }
        }
        (t, force) = (node, forces(node, Side::After));
        record(&mut snapshots, times, t, &state, &force);
    }
    snapshots
}

/// Appends a snapshot of `state` for every output time not yet recorded that is at or before
/// `t`.
fn record(snapshots: &mut Vec<Snapshot>, times: &[f64], t: f64, state: &[[f64; 2]], force: &[f64]) {
    while let Some(&time) = times.get(snapshots.len()).filter(|&&time| time <= t) {
        snapshots.push(Snapshot {
            time,
            state: state.to_vec(),
            force: force.to_vec(),
        });
    }
}

/// Mean of φ² over [0, 1] by 4-point Gauss–Legendre on panels finer than the mode's waves.
fn mean_square(shape: &ModeShape, n: u32) -> f64 {
    const NODES: [f64; 4] = [
        -0.861_136_311_594_052_6,
        -0.339_981_043_584_856_3,
        0.339_981_043_584_856_3,
        0.861_136_311_594_052_6,
    ];
    const WEIGHTS: [f64; 4] = [
        0.347_854_845_137_453_9,
        0.652_145_154_862_546_1,
        0.652_145_154_862_546_1,
        0.347_854_845_137_453_9,
    ];
    let panels = 16 * (n as usize + 2);
    let half = 0.5 / panels as f64;
    (0..panels)
        .map(|p| {
            let centre = (2 * p + 1) as f64 * half;
            NODES
                .iter()
                .zip(WEIGHTS)
                .map(|(&x, w)| w * shape.at(centre + half * x).0.powi(2))
                .sum::<f64>()
                * half
        })
        .sum()
}

/// The exact step of one mode over one step length, cached for repeated lengths.
#[derive(Default)]
struct Stepper {
    cache: Vec<(f64, Step)>,
}

impl Stepper {
    fn get(&mut self, omega: f64, damping: f64, h: f64, mode: usize) -> Step {
        if self.cache.len() <= mode {
            self.cache.resize(mode + 1, (f64::NAN, Step::default()));
        }
        let (cached_h, step) = &mut self.cache[mode];
        if *cached_h != h {
            *step = Step::exact(omega, damping, h);
            *cached_h = h;
        }
        *step
    }
}

/// The top two rows of exp(G h) for the generator G of [q, q̇, f, ḟ]:
/// q̇ = q̇, q̈ = f − 2ζω q̇ − ω² q, ḟ = ḟ, f̈ = 0.
#[derive(Clone, Copy, Debug, Default)]
struct Step {
    rows: [[f64; 4]; 2],
    h: f64,
}

impl Step {
    fn exact(omega: f64, damping: f64, h: f64) -> Step {
        #[rustfmt::skip]
        let generator = Matrix4::new(
            0.0, 1.0, 0.0, 0.0,
            -omega * omega, -2.0 * damping * omega, 1.0, 0.0,
            0.0, 0.0, 0.0, 1.0,
            0.0, 0.0, 0.0, 0.0,
        );
        let e = (generator * h).exp();
        let row = |i: usize| [e[(i, 0)], e[(i, 1)], e[(i, 2)], e[(i, 3)]];
        Step {
            rows: [row(0), row(1)],
            h,
        }
    }

    fn advance(&self, [q, v]: [f64; 2], f0: f64, f1: f64) -> [f64; 2] {
        let x = [q, v, f0, (f1 - f0) / self.h];
        self.rows
            .map(|r| r[0] * x[0] + r[1] * x[1] + r[2] * x[2] + r[3] * x[3])
    }
}

/// The modal state at one output time.
#[derive(Clone, Debug)]
pub(crate) struct Snapshot {
    pub(crate) time: f64,
    /// [q, q̇] per mode.
    pub(crate) state: Vec<[f64; 2]>,
    /// Modal force per mode at that time.
    pub(crate) force: Vec<f64>,
}

/// The beam's motion at the requested times.
#[derive(Clone, Debug)]
pub struct Response {
    snapshots: Vec<Snapshot>,
}

/// The beam at one point and instant.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Motion {
    /// Deflection, m, positive downward.
    pub deflection: f64,
    /// Velocity of the deflection, m/s.
    pub velocity: f64,
    /// Slope of the axis dv/dx, rad (positive where the deflection grows with x).
    pub slope: f64,
    /// Acceleration of the deflection, m/s².
    pub acceleration: f64,
    /// Bending moment, N·m, sagging positive.
    pub moment: f64,
}

impl Response {
    /// How many output times there are.
    pub fn len(&self) -> usize {
        self.snapshots.len()
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.snapshots.is_empty()
    }

    /// The modal coordinates q_n at output `k` (metres of the normalised mode shape).
    pub fn modal(&self, k: usize) -> Vec<f64> {
        self.snapshots[k].state.iter().map(|s| s[0]).collect()
    }

    /// The dynamic part of the deflection at output `k`: (mode number from 1, q_n − f_n/ω_n²),
    /// the amplitude of each normalised mode shape to add to the static deflection of
    /// `ModalBeam::static_loads` at that instant (the mode-acceleration method).
    pub fn dynamic_amplitudes(&self, beam: &ModalBeam, k: usize) -> Vec<(u32, f64)> {
        let snap = &self.snapshots[k];
        (1..)
            .zip(&beam.modes)
            .zip(snap.state.iter().zip(&snap.force))
            .map(|((n, mode), ([q, _], f))| (n, dynamic_amplitude(mode, *q, *f)))
            .collect()
    }

    /// The motion at x (m) at output `k`, by the mode-acceleration method.
    pub fn at(&self, beam: &ModalBeam, loads: &[TimeLoad], k: usize, x: f64) -> Motion {
        let snap = &self.snapshots[k];
        let stat = LinearBeam::solve(
            beam.support,
            beam.length,
            &beam.static_loads(loads, snap.time),
            0.0,
        )
        .at(x);
        let xi = x / beam.length;
        let mut motion = Motion {
            deflection: stat.v / beam.ei,
            velocity: 0.0,
            slope: stat.slope / beam.ei,
            acceleration: 0.0,
            moment: stat.moment,
        };
        let l2 = beam.length * beam.length;
        for ((mode, [q, v]), f) in beam.modes.iter().zip(&snap.state).zip(&snap.force) {
            let (phi, dphi, curvature) = mode.shape.at(xi);
            let w2 = mode.omega * mode.omega;
            let dynamic = dynamic_amplitude(mode, *q, *f);
            let accel = f - 2.0 * beam.damping * mode.omega * v - w2 * q;
            motion.deflection += dynamic * phi;
            motion.velocity += v * phi;
            motion.slope += dynamic * dphi / beam.length;
            motion.acceleration += accel * phi;
            // v positive downward and M sagging positive: M = −EI v″.
            motion.moment -= beam.ei * dynamic * curvature / l2;
        }
        motion
    }
}

/// The part of modal coordinate q that the static solution of the same forces does not hold:
/// q − f/ω², f the modal force (acceleration) at that instant.
fn dynamic_amplitude(mode: &Mode, q: f64, f: f64) -> f64 {
    q - f / (mode.omega * mode.omega)
}

#[cfg(test)]
pub(crate) mod tests;
