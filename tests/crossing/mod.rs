//! The crossing shared by the tests of the flow between frames (tests/sequences.rs) and of the
//! point tracks (tests/tracks.rs): a recipe of a beam crossed by one axle, filmed side-on, and
//! its closed-form response (`ModalBeam`), the independent truth both compare with.

use super::common;
use shmgen::mechanics::Support;
use shmgen::mechanics::dynamics::{Axle, ModalBeam, TimeLoad};
use std::path::Path;

/// The axle's speed, m/s.
pub const CROSSING_SPEED: f64 = 8.0;

/// A 2 m steel beam 0.1 × 0.2 m, simply supported, crossed at 8 m/s by one 3e5 N axle, filmed
/// side-on from 0.6 m at 30 fps (8 frames over the crossing); `mount` shakes the camera;
/// `outputs` go into `dataset.outputs`.
pub fn crossing_recipe(mount: &str, outputs: &str) -> String {
    format!(
        r#"dataset(#{{
    name: "flow", seed: 5, samples: 1, views: 1, outputs: [{outputs}],
    sequence: #{{ duration: 0.25, fps: {CROSSING_FPS} {mount} }},
    camera: #{{ width: 160, height: 120, fov_y: deg(60),
        fixed: [#{{ position: [1.0, -0.6, 0.12], target: [1.0, 0.0, 0.0] }}] }},
    scene: |rng| {{
        let b = beam(#{{ length: 2.0, width: 0.1, height: 0.2 }});
        b.simply_supported();
        b.theory("euler_bernoulli");
        b.at(1.0, 0.0, 0.0);
        b.vehicle([[0.0, {CROSSING_FORCE}]], {CROSSING_SPEED}, 0.0); b.damping(0.03); b.modes(6);
        b
    }},
}});
"#
    )
}

pub const CROSSING_FPS: f64 = 30.0;
pub const CROSSING_FORCE: f64 = 3e5;
pub const CROSSING_FRAMES: usize = 8;

/// Frame `frame` of view 0 of sample 0: its depth, mask and record.
pub fn frame_view(out: &Path, frame: usize) -> common::View {
    let path = |kind: &str| out.join(format!("samples/0000/000000_00_f{frame:04}.{kind}"));
    let (width, height, _, mask) = common::read_png(&path("mask.png"));
    common::View {
        width,
        height,
        depth: common::read_exr(&path("depth.exr")),
        mask,
        json: common::read_json(&path("json")),
    }
}

/// The crossing's beam as `ModalBeam` (E = 210 GPa, steel), its load and its response at the
/// frames' instants: the independent truth of the flow between frames.
pub struct Crossing {
    beam: ModalBeam,
    loads: Vec<TimeLoad>,
    response: shmgen::mechanics::dynamics::Response,
}

impl Crossing {
    pub fn new() -> Self {
        let (width, height, length): (f64, f64, f64) = (0.1, 0.2, 2.0);
        let ei = 210e9 * width * height.powi(3) / 12.0;
        let mass = 7850.0 * width * height;
        let beam = ModalBeam::new(Support::SimplySupported, length, ei, mass, 0.03, 6).unwrap();
        let loads = vec![TimeLoad::Vehicle {
            axles: vec![Axle {
                behind: 0.0,
                force: CROSSING_FORCE,
            }],
            speed: CROSSING_SPEED,
            enters: 0.0,
        }];
        let times: Vec<f64> = (0..CROSSING_FRAMES)
            .map(|k| k as f64 / CROSSING_FPS)
            .collect();
        let response = beam.respond(&loads, 0.0, &times, 64);
        Crossing {
            beam,
            loads,
            response,
        }
    }

    /// (deflection downward, slope) of the axis at `x` at frame `k`.
    pub fn axis(&self, k: usize, x: f64) -> (f64, f64) {
        let m = self
            .response
            .at(&self.beam, &self.loads, k, x.clamp(0.0, 2.0));
        (m.deflection, m.slope)
    }

    /// Where world point `p`, seen on the beam at frame `k`, is at frame `other`: plane
    /// sections rotating with the slope (a fibre `e` above the axis at x moves by (e·w′, 0,
    /// −w), w downward), to first order in the slope (the neglected cos and axial-shortening
    /// terms are below 2·10⁻⁵ m here, 0.007 px).
    pub fn carried(&self, p: [f64; 3], k: usize, other: usize) -> [f64; 3] {
        // The material point's axial coordinate x and height e above the axis, from where
        // frame k has it: p = (x + e·w′(x), y, e − w(x)), solved by fixed point.
        let (mut x, mut e) = (p[0], p[2]);
        for _ in 0..8 {
            let (w, slope) = self.axis(k, x);
            e = p[2] + w;
            x = p[0] - e * slope;
        }
        let (w, slope) = self.axis(other, x);
        [x + e * slope, p[1], e - w]
    }
}
