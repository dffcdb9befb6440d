//! Daylight at a shaded point: how much of the sun's finite disk the point sees (soft shadow
//! edges, the penumbra), how much of the sky above and the ground below its hemisphere sees
//! (ambient occlusion), and the light a lit ground plane bounces up once.
//!
//! Owns: the fixed ray patterns over a disk and a hemisphere, their turn per pixel, and the
//! occlusion and penumbra estimates. Must not touch: images, backdrops, materials' colours or
//! anything of the scene beyond the traced mesh. Nothing here is random: the pattern is a
//! fixed spiral, turned by an angle hashed from the pixel's position, so neighbouring pixels
//! sample different directions (noise, not banding) and the same pixel always the same ones,
//! whatever the thread count. See docs/daylight.md for the models and their sources.

use super::trace::TraceMesh;
use crate::materials::{EnvironmentLight, GroundBounce, Lighting, Sky, Sun};
use glam::DVec3;

/// Points spread evenly over the unit disk: Vogel's (1979) spiral, r = √((i + ½)/n) at the
/// golden angle, equal area per point. One point is the centre.
pub(super) struct DiskPattern(Vec<(f64, f64)>);

impl DiskPattern {
    /// Whether the pattern has no point (no ray is cast).
    pub(super) fn is_empty(&self) -> bool {
        self.0.is_empty()
    }

    /// `n` points (none for 0).
    pub(super) fn new(n: u32) -> Self {
        if n == 1 {
            return DiskPattern(vec![(0.0, 0.0)]);
        }
        let golden = std::f64::consts::PI * (3.0 - libm::sqrt(5.0));
        DiskPattern(
            (0..n)
                .map(|i| {
                    let r = libm::sqrt((f64::from(i) + 0.5) / f64::from(n));
                    let a = f64::from(i) * golden;
                    (r * libm::cos(a), r * libm::sin(a))
                })
                .collect(),
        )
    }

    /// The largest distance of a point from the disk's centre (0 without points): turning
    /// the pattern keeps it.
    fn widest(&self) -> f64 {
        self.0
            .iter()
            .map(|&(x, y)| libm::sqrt(x * x + y * y))
            .fold(0.0, f64::max)
    }

    /// The points turned by the angle whose (cos, sin) is `turn`.
    fn turned(&self, (c, s): (f64, f64)) -> impl Iterator<Item = (f64, f64)> + '_ {
        self.0
            .iter()
            .map(move |&(x, y)| (x * c - y * s, x * s + y * c))
    }
}

/// (cos, sin) of an angle hashed from the image point (u, v): the same pixel and sub-pixel
/// sample always turn the pattern alike.
pub(super) fn pixel_turn(u: f64, v: f64) -> (f64, f64) {
    hashed_turn(u.to_bits() ^ v.to_bits().rotate_left(29))
}

/// (cos, sin) of an angle hashed from `key`: a fixed, well-spread turn for each key.
pub(super) fn hashed_turn(key: u64) -> (f64, f64) {
    let mut h = key ^ 0x9e37_79b9_7f4a_7c15;
    // splitmix64's finaliser (Steele, Lea & Flood 2014).
    h = (h ^ (h >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    h = (h ^ (h >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    h ^= h >> 31;
    let angle = (h >> 11) as f64 * (std::f64::consts::TAU / (1u64 << 53) as f64);
    (libm::cos(angle), libm::sin(angle))
}

/// Two unit vectors completing `n` (unit) to a right-handed orthonormal frame, without a
/// branch on a near-zero component (Duff et al. 2017).
fn frame(n: DVec3) -> (DVec3, DVec3) {
    let sign = if n.z >= 0.0 { 1.0 } else { -1.0 };
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    (
        DVec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
        DVec3::new(b, sign + n.y * n.y * a, -n.y),
    )
}

/// Fraction of the sun's disk that point `p` (outward normal `n`, facing the sun) sees past
/// the mesh: rays towards points spread evenly over the disk, each blocked or not. A point
/// sun, or a single ray, gives 0 or 1 along the sun's centre (a hard shadow).
pub(super) fn sun_visibility(
    mesh: &TraceMesh,
    p: DVec3,
    n: DVec3,
    sun: &Sun,
    disk: &DiskPattern,
    turn: (f64, f64),
) -> f64 {
    if disk.0.len() <= 1 || sun.angular_diameter <= 0.0 {
        return if mesh.occluded(p, n, sun.direction) {
            0.0
        } else {
            1.0
        };
    }
    // A disk of angular radius θ/2 seen at unit distance: tan(θ/2) across.
    let spread = libm::tan(0.5 * sun.angular_diameter);
    let (t, b) = frame(sun.direction);
    let seen = disk
        .turned(turn)
        .filter(|&(x, y)| {
            let d = (sun.direction + spread * (x * t + y * b)).normalize();
            n.dot(d) > 0.0 && !mesh.occluded(p, n, d)
        })
        .count();
    seen as f64 / disk.0.len() as f64
}

/// Whether a face turned to `n` traces shadow rays under `lighting` (`LightRays::traces_sun`).
fn traces_sun(lighting: &Lighting, n: DVec3) -> bool {
    lighting.shadows && lighting.sun.is_some_and(|sun| n.dot(sun.direction) > 0.0)
}

/// Whether points trace `hemisphere`'s rays under `lighting` (`LightRays::traces_sky`).
fn traces_sky(lighting: &Lighting, hemisphere: &DiskPattern) -> bool {
    let surrounding =
        lighting.environment.is_some() || lighting.sky.is_some() || lighting.ground.is_some();
    surrounding && !hemisphere.is_empty()
}

/// The least rise (the z of the unit direction) of any ray a point facing straight up (+z)
/// casts under `lighting` with these patterns: towards the sun's disk (when it traces them)
/// and over the hemisphere (when it traces them), less 10⁻⁹ of it for rounding; None when
/// some such ray may run level or down (a sun at the horizon), or when the point casts none.
pub(super) fn least_rise_facing_up(
    lighting: &Lighting,
    sun_disk: &DiskPattern,
    hemisphere: &DiskPattern,
) -> Option<f64> {
    let sun = lighting
        .sun
        .filter(|_| traces_sun(lighting, DVec3::Z))
        .map(|sun| sun_ray_rise(&sun, sun_disk));
    // Malley's lift of a disk point at radius r rises √(1 − r²) off the face.
    let sky = traces_sky(lighting, hemisphere).then(|| {
        let r = hemisphere.widest();
        libm::sqrt((1.0 - r * r).max(0.0))
    });
    let least = match (sun, sky) {
        (Some(a), Some(b)) => a.min(b),
        (a, b) => a.or(b)?,
    };
    let least = least * (1.0 - 1e-9);
    (least > 0.0).then_some(least)
}

/// The least z of the unit directions `sun_visibility` casts towards `sun`'s disk: the centre
/// tipped by at most `spread` = tan(θ/2) sideways, then normalised, loses at most
/// (s_z − spread) / √(1 + spread²) of its rise (a lower bound: the pattern stays within the
/// unit disk).
fn sun_ray_rise(sun: &Sun, disk: &DiskPattern) -> f64 {
    if disk.0.len() <= 1 || sun.angular_diameter <= 0.0 {
        return sun.direction.z;
    }
    let spread = libm::tan(0.5 * sun.angular_diameter);
    (sun.direction.z - spread) / libm::sqrt(1.0 + spread * spread)
}

/// Radiance of the ground as a face sees it from above, per channel, times π: the sky's own
/// ground colour, or the light an infinite Lambertian plane of albedo ρ bounces up when lit by
/// the ambient term, the whole sky and the unshadowed sun (ρ E_horizontal, Lambert's law).
fn ground_exitance(lighting: &Lighting, ground: Option<GroundBounce>, p: DVec3) -> [f64; 3] {
    match ground {
        Some(g) if p.z >= g.height => {
            let sun = lighting.sun.map(|s| (s.colour, s.direction.z.max(0.0)));
            std::array::from_fn(|k| {
                let sky = lighting.sky.map_or(0.0, |s| s.sky[k]);
                let sun = sun.map_or(0.0, |(c, up)| c[k] * up);
                g.albedo[k] * (lighting.ambient + sky + sun)
            })
        }
        Some(_) => [0.0; 3],
        None => lighting.sky.map_or([0.0; 3], |s| s.ground),
    }
}

/// What a shaded point sees of the lights, each a share in [0, 1]: of the sun's disk, of the
/// upward and of the downward cosine-weighted hemisphere rays, and of all of them. 1 where
/// nothing was traced (no shadows, a face turned from the sun, no occlusion rays): the light
/// then reaches the point whole, and multiplying by 1 leaves its bits as they were.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Openness {
    pub sun: f64,
    pub up: f64,
    pub down: f64,
    pub all: f64,
}

impl Openness {
    /// Nothing blocks any light.
    pub const OPEN: Openness = Openness {
        sun: 1.0,
        up: 1.0,
        down: 1.0,
        all: 1.0,
    };
}

/// The rays a shaded point casts towards the lights: the mesh they may meet, the light, and
/// the patterns over the sun's disk and the hemisphere.
pub(super) struct LightRays<'a> {
    pub mesh: &'a TraceMesh,
    pub lighting: &'a Lighting,
    pub sun_disk: &'a DiskPattern,
    pub hemisphere: &'a DiskPattern,
}

impl LightRays<'_> {
    /// The `Openness` of point `p` with facing `n`, the patterns turned by `turn()`.
    pub fn openness(&self, p: DVec3, n: DVec3, turn: impl Fn() -> (f64, f64)) -> Openness {
        let mut open = Openness::OPEN;
        if self.traces_sun(n) {
            open.sun = self.sun_share(p, n, turn());
        }
        if self.traces_sky() {
            [open.up, open.down, open.all] = self.sky_shares(p, n, turn());
        }
        open
    }

    /// Whether a face turned to `n` traces shadow rays: when the sun casts shadows and the
    /// face is turned to it (a face turned away is unlit either way).
    pub fn traces_sun(&self, n: DVec3) -> bool {
        traces_sun(self.lighting, n)
    }

    /// Whether points trace hemisphere rays: when a sky, ground or environment lights them
    /// and the pattern has rays.
    pub fn traces_sky(&self) -> bool {
        traces_sky(self.lighting, self.hemisphere)
    }

    /// The share of the sun's disk `p` sees (1 without a sun).
    pub fn sun_share(&self, p: DVec3, n: DVec3, turn: (f64, f64)) -> f64 {
        self.lighting.sun.map_or(1.0, |sun| {
            sun_visibility(self.mesh, p, n, &sun, self.sun_disk, turn)
        })
    }

    /// Whether `p` looks enclosed: a ray along `n` and eight rays 80° from it, nearly along
    /// the face, all meet the mesh. A point on a visible face sees out along one of them
    /// unless it lies deep in a crevice (even under a beam, or in the corner of a wall and a
    /// floor, a ray along the floor escapes); a point inside a solid (a lattice corner on a
    /// face's plane extended into a neighbouring part) sees out along none.
    pub fn enclosed(&self, p: DVec3, n: DVec3) -> bool {
        let (t, b) = frame(n);
        let (along, lift) = (80f64.to_radians().sin(), 80f64.to_radians().cos());
        let sideways = (0..8).map(|k| {
            let a = f64::from(k) * std::f64::consts::FRAC_PI_4;
            (libm::cos(a) * t + libm::sin(a) * b) * along + n * lift
        });
        std::iter::once(n)
            .chain(sideways)
            .all(|d| self.mesh.occluded(p, n, d.normalize()))
    }

    /// The shares of the upward, the downward and all hemisphere rays that leave `p`.
    pub fn sky_shares(&self, p: DVec3, n: DVec3, turn: (f64, f64)) -> [f64; 3] {
        let ground = self.lighting.ground;
        let ((up, down), all) =
            hemisphere_visibility(self.mesh, ground, p, n, self.hemisphere, turn);
        [up, down, all]
    }
}

/// Light from the sky above and the ground below on a face with normal `n` at `p`: the
/// hemispherical model (sky weighted by (1 + n_z)/2, ground by (1 − n_z)/2) with each half
/// scaled by the share of its cosine-weighted directions that escape the mesh (`open.up`,
/// `open.down`; a ray down only counts as blocked when it meets the mesh above the ground
/// plane). Returns (occluded, unoccluded) irradiance.
pub(super) fn sky_light(
    lighting: &Lighting,
    p: DVec3,
    n: DVec3,
    open: Openness,
) -> ([f64; 3], [f64; 3]) {
    let sky = lighting.sky.map_or([0.0; 3], |s: Sky| s.sky);
    let ground = ground_exitance(lighting, lighting.ground, p);
    let up = 0.5 * (1.0 + n.z);
    let unoccluded: [f64; 3] = std::array::from_fn(|k| sky[k] * up + ground[k] * (1.0 - up));
    let seen = std::array::from_fn(|k| sky[k] * up * open.up + ground[k] * (1.0 - up) * open.down);
    (seen, unoccluded)
}

/// Light from an environment map on a face with normal `n`: its order-2 SH irradiance, scaled
/// by the share `open.all` of all the cosine-weighted hemisphere directions that escape the
/// mesh (a ray down stops short of the ground plane, which the map already shows). Returns
/// (occluded, unoccluded).
pub(super) fn environment_light(
    environment: &EnvironmentLight,
    n: DVec3,
    open: Openness,
) -> ([f64; 3], [f64; 3]) {
    let unoccluded = environment.diffuse(n);
    (unoccluded.map(|c| c * open.all), unoccluded)
}

/// Shares of the upward and of the downward rays of a cosine-weighted hemisphere about `n`
/// (Malley's method: the disk pattern lifted onto the hemisphere) that leave `p` unblocked (1
/// for a half without rays), and the share of all of them.
fn hemisphere_visibility(
    mesh: &TraceMesh,
    ground: Option<GroundBounce>,
    p: DVec3,
    n: DVec3,
    hemisphere: &DiskPattern,
    turn: (f64, f64),
) -> ((f64, f64), f64) {
    let (t, b) = frame(n);
    let (mut up, mut up_seen, mut down, mut down_seen) = (0u32, 0u32, 0u32, 0u32);
    for (x, y) in hemisphere.turned(turn) {
        let d = (x * t + y * b + libm::sqrt((1.0 - x * x - y * y).max(0.0)) * n).normalize();
        if d.z > 0.0 {
            up += 1;
            up_seen += u32::from(!mesh.occluded(p, n, d));
        } else {
            down += 1;
            // Stop short of the ground plane: the plane is the light, not a blocker.
            let reach = ground
                .filter(|g| p.z > g.height && d.z < 0.0)
                .map_or(f64::INFINITY, |g| 0.999 * (p.z - g.height) / -d.z);
            down_seen += u32::from(!mesh.occluded_within(p, n, d, reach));
        }
    }
    let share = |seen: u32, all: u32| {
        if all == 0 {
            1.0
        } else {
            f64::from(seen) / f64::from(all)
        }
    };
    (
        (share(up_seen, up), share(down_seen, down)),
        share(up_seen + down_seen, up + down),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Mesh;

    /// A mesh of axis-aligned quads, each given by its lower and upper corners (one extent 0).
    fn quads(boxes: &[([f64; 3], [f64; 3])]) -> TraceMesh {
        let mut mesh = Mesh {
            positions: vec![],
            triangles: vec![],
        };
        for &(lo, hi) in boxes {
            let flat = (0..3).find(|&k| lo[k] == hi[k]).expect("a flat quad");
            let (i, j) = ((flat + 1) % 3, (flat + 2) % 3);
            let corner = |a: bool, b: bool| {
                let mut c = lo;
                c[i] = if a { hi[i] } else { lo[i] };
                c[j] = if b { hi[j] } else { lo[j] };
                DVec3::from_array(c)
            };
            let base = mesh.positions.len() as u32;
            mesh.positions.extend([
                corner(false, false),
                corner(true, false),
                corner(true, true),
                corner(false, true),
            ]);
            mesh.triangles
                .extend([[base, base + 1, base + 2], [base, base + 2, base + 3]]);
        }
        TraceMesh::build(&mesh)
    }

    /// Visible fraction of a disk of radius r whose centre lies `x` beyond a straight edge
    /// (x < 0: the centre is behind the edge): 1 − the circular segment's share.
    fn disk_beyond_edge(x: f64, r: f64) -> f64 {
        if x >= r {
            return 1.0;
        }
        if x <= -r {
            return 0.0;
        }
        let h = r - x; // depth of the hidden segment
        let segment = r * r * (1.0 - h / r).acos() - (r - h) * (2.0 * r * h - h * h).sqrt();
        1.0 - segment / (std::f64::consts::PI * r * r)
    }

    /// A sun straight overhead behind a large plate whose edge runs along y at x = 0, height
    /// H above the ground: the penumbra on the ground spans H·θ, and the share of the disk seen
    /// follows the circular segment that the edge cuts off the disk's image.
    #[test]
    fn the_penumbra_of_an_edge_is_height_times_the_suns_angular_diameter() {
        let height = 2.0;
        // A plate covering x < 0, far wider than the penumbra.
        let mesh = quads(&[([-50.0, -50.0, height], [0.0, 50.0, height])]);
        let theta = 2.0_f64.to_radians(); // a wide sun makes a 7 cm penumbra
        let sun = Sun {
            direction: DVec3::Z,
            colour: [1.0; 3],
            angular_diameter: theta,
            shadow_rays: 256,
        };
        let disk = DiskPattern::new(sun.shadow_rays);
        let radius = height * (0.5 * theta).tan(); // the disk's image on the ground
        let mut width_seen = (f64::INFINITY, f64::NEG_INFINITY);
        for step in -40..=40 {
            let x = f64::from(step) * radius / 30.0;
            let p = DVec3::new(x, 0.3, 0.0);
            let seen = sun_visibility(&mesh, p, DVec3::Z, &sun, &disk, pixel_turn(x, 0.3));
            let expected = disk_beyond_edge(x, radius);
            assert!(
                (seen - expected).abs() < 0.03,
                "x = {x:.4} m: saw {seen:.3} of the sun, the segment gives {expected:.3}"
            );
            if seen > 0.0 && seen < 1.0 {
                width_seen = (width_seen.0.min(x), width_seen.1.max(x));
            }
        }
        let width = width_seen.1 - width_seen.0;
        let analytic = height * theta;
        assert!(
            (width - analytic).abs() < 0.1 * analytic,
            "penumbra {width:.4} m, H·θ = {analytic:.4} m"
        );
    }

    #[test]
    fn a_point_sun_or_one_ray_casts_a_hard_shadow() {
        let mesh = quads(&[([-50.0, -50.0, 2.0], [0.0, 50.0, 2.0])]);
        for (diameter, rays) in [(0.0, 16), (0.02, 1)] {
            let sun = Sun {
                direction: DVec3::Z,
                colour: [1.0; 3],
                angular_diameter: diameter,
                shadow_rays: rays,
            };
            let disk = DiskPattern::new(rays);
            for (x, lit) in [(-0.01, 0.0), (0.01, 1.0)] {
                let p = DVec3::new(x, 0.0, 0.0);
                let seen = sun_visibility(&mesh, p, DVec3::Z, &sun, &disk, pixel_turn(x, 0.0));
                assert_eq!(seen, lit, "diameter {diameter}, {rays} rays, x = {x}");
            }
        }
    }

    /// A point on the ground at distance d from a long wall of height h sees the wall over
    /// elevations up to β = atan(h/d); an infinitely long strip hides (1 − cos β)/2 of a
    /// horizontal face's cosine-weighted sky (the view factor of a 2-D strip, Hottel's crossed
    /// strings; Modest, Radiative Heat Transfer, 3rd ed., §4.4).
    #[test]
    fn sky_occlusion_next_to_a_wall_matches_the_strip_view_factor() {
        let (h, length) = (3.0, 400.0);
        let mesh = quads(&[([1.0, -length, 0.0], [1.0, length, h])]);
        let hemisphere = DiskPattern::new(1024);
        for d in [0.25, 1.0, 3.0, 9.0] {
            let p = DVec3::new(1.0 - d, 0.0, 0.0);
            let ((above, below), _) =
                hemisphere_visibility(&mesh, None, p, DVec3::Z, &hemisphere, pixel_turn(d, 0.0));
            let beta = (h / d).atan();
            let expected = 1.0 - 0.5 * (1.0 - beta.cos());
            assert!(
                (above - expected).abs() < 0.02,
                "d = {d}: sky seen {above:.3}, view factor gives {expected:.3}"
            );
            assert_eq!(below, 1.0, "no ray of an upward face goes down");
        }
    }

    /// A face turned straight down above an infinite ground of albedo ρ, lit by an overhead
    /// sun of irradiance E and nothing else, receives ρE: the plane's exitance, all of its
    /// hemisphere filled by the plane. Sideways it receives half; facing up, none.
    #[test]
    fn a_lit_ground_bounces_albedo_times_its_irradiance() {
        let elevation: f64 = 0.6;
        let lighting = Lighting {
            ambient: 0.0,
            studio: None,
            sun: Some(Sun {
                direction: DVec3::new(elevation.cos(), 0.0, elevation.sin()),
                colour: [2.0; 3],
                angular_diameter: 0.0,
                shadow_rays: 1,
            }),
            sky: None,
            environment: None,
            shadows: true,
            ground: Some(GroundBounce {
                height: 0.0,
                albedo: [0.3, 0.2, 0.1],
            }),
            film: Default::default(),
        };
        let e = 2.0 * elevation.sin();
        for (n, share) in [(-DVec3::Z, 1.0), (DVec3::X, 0.5), (DVec3::Z, 0.0)] {
            let p = DVec3::new(3.0, 0.0, 1.0);
            let (got, _) = sky_light(&lighting, p, n, Openness::OPEN);
            for (k, rho) in [0.3, 0.2, 0.1].into_iter().enumerate() {
                assert!((got[k] - rho * e * share).abs() < 1e-12, "{n}: {got:?}");
            }
        }
        // Below the ground nothing bounces up.
        let under = sky_light(
            &lighting,
            DVec3::new(0.0, 0.0, -1.0),
            -DVec3::Z,
            Openness::OPEN,
        );
        assert_eq!(under.0, [0.0; 3]);
    }

    /// The down rays of a face just above the ground stop at the plane: a ground traced as
    /// geometry does not hide itself.
    #[test]
    fn the_ground_plane_does_not_occlude_its_own_bounce() {
        let mesh = quads(&[([-50.0, -50.0, 0.0], [50.0, 50.0, 0.0])]);
        let ground = Some(GroundBounce {
            height: 0.0,
            albedo: [0.5; 3],
        });
        let hemisphere = DiskPattern::new(64);
        let p = DVec3::new(0.0, 0.0, 0.5);
        let ((_, below), _) =
            hemisphere_visibility(&mesh, ground, p, DVec3::X, &hemisphere, (1.0, 0.0));
        assert_eq!(below, 1.0);
        let ((_, blocked), _) =
            hemisphere_visibility(&mesh, None, p, DVec3::X, &hemisphere, (1.0, 0.0));
        // Only rays grazing past the 50 m floor's edge escape.
        assert!(
            blocked < 0.05,
            "without the plane declared, the floor blocks: {blocked}"
        );
    }

    #[test]
    fn the_frame_is_orthonormal_for_every_facing() {
        for n in [
            DVec3::Z,
            -DVec3::Z,
            DVec3::X,
            DVec3::new(0.3, -0.4, -0.866).normalize(),
        ] {
            let (t, b) = frame(n);
            for (x, y) in [(t, b), (t, n), (b, n)] {
                assert!(x.dot(y).abs() < 1e-12);
            }
            assert!((t.length() - 1.0).abs() < 1e-12 && (b.length() - 1.0).abs() < 1e-12);
            assert!((t.cross(b) - n).length() < 1e-12);
        }
    }
}
