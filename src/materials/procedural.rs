//! Procedural materials: a `Material` made concrete for one sample (its noise seed and drawn
//! variations) and evaluated at points of the undeformed surface.
//!
//! Every length is physical (metres, times the material's `scale`), every pattern is a function
//! of the 3D rest position, and every feature finer than the pixel footprint is averaged out
//! (fractal octaves fade, thin lines lighten by the fraction of the pixel they cover).

use super::noise::{Field, LANES, Ladder, Noise, SpanLadder, pair, smoothstep, unit};
use super::{Base, Condition, ConditionKind, Material, Species, Texture};
use crate::seeds::Stream;
use glam::DVec3;
use serde::Serialize;
use std::sync::LazyLock;

/// What a sample drew for its material: where its texture is cut from, how far the wood's
/// pith lies from the piece's axis (metres) and a brightness variation.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, schemars::JsonSchema)]
pub struct MaterialDraw {
    /// Offset of the sample's cut of the procedural textures (metres).
    pub texture_offset: [f64; 3],
    /// Distance of the timber's pith from the piece's grain axis, metres (0.15–0.6 times the
    /// material's `scale`); drawn for every base, used by timber only.
    pub pith_distance: f64,
    /// Factor on the albedo (1 for plain colours).
    pub brightness: f64,
}

/// Where a ray meets a surface, in the structure's undeformed state.
#[derive(Clone, Copy, Debug)]
pub struct SurfacePoint {
    /// Position on the undeformed surface (metres, world axes before deformation).
    pub rest: DVec3,
    /// Unit outward normal of the undeformed surface.
    pub rest_normal: DVec3,
    /// Size of the pixel on the surface (metres), widened at grazing incidence.
    pub footprint: f64,
}

/// Direction along which wood grain, brushing and fibres run, and a point on the piece's axis.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Grain {
    /// Unit direction of the grain, world axes.
    pub axis: DVec3,
    /// A point on the piece's axis, world coordinates before deformation, metres.
    pub centre: DVec3,
    /// Lowest z of the piece's undeformed surface, metres: dirt gathers above it.
    pub bottom: f64,
    /// Highest z of the piece's undeformed surface, metres: rain runs down from it.
    pub top: f64,
}

/// What shading needs to know about a surface point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Surface {
    /// Linear-light albedo.
    pub albedo: [f64; 3],
    /// Microfacet roughness in (0, 1]: 1 is fully matte.
    pub roughness: f64,
    /// Specular reflectance at normal incidence.
    pub specular: f64,
    /// Whether the point lies on a crack (the crack mask label).
    pub crack: bool,
}

/// A material with the random choices of one sample made: where its texture is cut from,
/// where the pith of timber lies, and a small variation of its colour.
#[derive(Clone, Debug)]
pub struct Shader {
    material: Material,
    noise: Noise,
    /// Added to every rest position, so each sample shows another part of the texture.
    offset: DVec3,
    /// Pith distance from the piece's axis as a multiple of 1 m, and the cosine and sine of its
    /// direction angle.
    pith: (f64, [f64; 2]),
    brightness: f64,
    /// The material's linear base colour times `brightness`.
    albedo: [f64; 3],
    /// Whether the surface varies from point to point (asked at every pixel).
    textured: bool,
}

/// Share of a pixel a crack must cover for the pixel to be labelled a crack.
pub const CRACK_LABEL_COVER: f64 = 0.2;

/// Steel sheet courses of a shell (silo, tank): plates 1.25 m high (the 1250 mm width of
/// rolled plate and of bolted-silo sheets), eight round a ring, alternate courses staggered by
/// half a sheet.
pub const COURSE_HEIGHT: f64 = 1.25;
/// Sheets round one course of a shell.
pub const SHEETS_PER_RING: f64 = 8.0;
/// Width of a weld seam or lap joint, metres.
const SEAM_WIDTH: f64 = 0.008;
/// Formwork: joints between plywood panels 1.2 m wide (the 1220 × 2440 mm sheet standing
/// across the piece), form ties every 0.6 m along it in rows 0.6 m apart from mid-height.
pub const FORM_PANEL: f64 = 1.2;
/// Spacing of form ties (and their holes), metres.
pub const TIE_SPACING: f64 = 0.6;
/// Radius of the cone-snap-tie holes left in the face, metres.
const TIE_RADIUS: f64 = 0.011;
/// Width of the grout line a panel joint leaves, metres.
const FORM_JOINT: f64 = 0.003;
/// Distance below its source (an edge, a seam) at which a run or stain has faded to a half.
const RUN_LENGTH: f64 = 0.35;
/// How weathered any outdoor paint is without a condition saying so (chalking, dirt, runs).
const PAINT_AGE: f64 = 0.35;

// The fractal fields of the bases and conditions, on the octave ladder (wavelengths are rungs:
// 1.28 m halved). Fields of one lane share the octaves they have in common, so lanes go by
// role: 0 a base's coarse pattern (and the rust tone, finer than any base's coarse pattern
// but the smoothest), 1 a base's fine pattern, 2 the rust patches (steel's mill-scale mottle
// is their coarse half, as rust starts where the mill scale is thin), 3 their ragged edges;
// 4–7 (a second lattice evaluation, paid only by materials with these conditions) weathering,
// moss and paint wear.
const STEEL_MOTTLE: Field = Field::new(2, 0.32, 4);
const BASE_FINE: Field = Field::new(1, 0.02, 3);
const SHEEN: Field = Field::new(0, 0.64, 3);
const PATINA: Field = Field::new(0, 0.16, 5);
const CONCRETE_MOTTLE: Field = Field::new(0, 0.32, 4);
const CONCRETE_FINE: Field = Field::new(1, 0.04, 3);
const RING_WANDER: Field = Field::new(0, 0.32, 3);
const SMOOTH: Field = Field::new(0, 0.04, 3);
const STONE: Field = Field::new(0, 0.08, 4);
const PAINT: Field = Field::new(0, 0.08, 3);
const RUST: Field = Field::new(2, 0.32, 6);
const RUST_EDGE: Field = Field::new(3, 0.02, 3);
const RUST_TONE: Field = Field::new(0, 0.04, 5);
/// Broad rust tone: whole patches lean orange or dark brown (rungs rust already evaluates).
const RUST_AGE: Field = Field::new(1, 0.16, 2);
/// Paint chalking and dirt, on the rungs paint's own field evaluates (free lanes 1 and 2).
const CHALK: Field = Field::new(1, 0.08, 3);
const GRIME: Field = Field::new(2, 0.08, 3);
/// Corrosion pits: the peaks of centimetre noise (rungs the rust's ragged edge evaluates).
const PITS: Field = Field::new(1, 0.01, 2);
const BLOTCH: Field = Field::new(4, 0.64, 4);
const WORN_SUBSTRATE: Field = Field::new(4, 0.04, 3);
const MOSS_PATCH: Field = Field::new(5, 0.32, 5);
const MOSS_TONE: Field = Field::new(6, 0.01, 3);
const WEAR: Field = Field::new(7, 0.16, 5);

/// Rust as it forms on structural steel: fresh orange-brown (lepidocrocite-rich), through
/// brown, to the dark brown of old compact rust (sRGB).
const RUST_LIGHT: [f64; 3] = [0.56, 0.3, 0.13];
const RUST_MID: [f64; 3] = [0.38, 0.2, 0.09];
const RUST_DARK: [f64; 3] = [0.2, 0.1, 0.055];
/// Paint that has chalked (binder eroded, pigment loose at the surface): pale and matte.
const CHALK_WHITE: [f64; 3] = [0.86, 0.86, 0.84];
/// Efflorescence: calcium carbonate washed out of concrete and dried white.
const EFFLORESCENCE: [f64; 3] = [0.88, 0.88, 0.85];
const MOSS: [f64; 3] = [0.27, 0.36, 0.12];
const MORTAR: [f64; 3] = [0.66, 0.64, 0.6];
/// Bare steel showing where paint has worn away.
const BARE_STEEL: [f64; 3] = [0.45, 0.45, 0.46];

/// The colours above in linear light, decoded once rather than at every point.
struct Palette {
    rust_light: [f64; 3],
    rust_mid: [f64; 3],
    rust_dark: [f64; 3],
    chalk: [f64; 3],
    efflorescence: [f64; 3],
    moss: [f64; 3],
    mortar: [f64; 3],
    bare_steel: [f64; 3],
}

static PALETTE: LazyLock<Palette> = LazyLock::new(|| Palette {
    rust_light: linear(RUST_LIGHT),
    rust_mid: linear(RUST_MID),
    rust_dark: linear(RUST_DARK),
    chalk: linear(CHALK_WHITE),
    efflorescence: linear(EFFLORESCENCE),
    moss: linear(MOSS),
    mortar: linear(MORTAR),
    bare_steel: linear(BARE_STEEL),
});

impl Shader {
    /// Draws the sample's choices for `material` from `stream` (a stream of its own, so a
    /// change of material never shifts the scene's or the cameras' random values).
    pub fn new(material: &Material, stream: &mut Stream) -> Self {
        let seed = stream.next_u64();
        let offset = DVec3::new(
            stream.uniform(-500.0, 500.0),
            stream.uniform(-500.0, 500.0),
            stream.uniform(-500.0, 500.0),
        );
        let distance = stream.uniform(0.15, 0.6);
        let (sin, cos) = libm::sincos(stream.uniform(0.0, std::f64::consts::TAU));
        let pith = (distance, [cos, sin]);
        let variation = if material.base == Base::Plain {
            0.0
        } else {
            0.05
        };
        let brightness = 1.0 + stream.uniform(-variation, variation);
        Shader {
            material: material.clone(),
            noise: Noise::new(seed),
            offset,
            pith,
            brightness,
            albedo: material.albedo().map(|c| c * brightness),
            textured: material.base != Base::Plain
                || !material.conditions.is_empty()
                || material.texture != Texture::Procedural,
        }
    }

    /// The material this shader draws.
    pub fn material(&self) -> &Material {
        &self.material
    }

    /// The surface without texture: the mean albedo and the material's finish.
    pub fn untextured(&self) -> Surface {
        Surface {
            albedo: self.albedo,
            roughness: self.material.roughness,
            specular: self.material.specular,
            crack: false,
        }
    }

    /// Whether the surface varies from point to point.
    pub fn textured(&self) -> bool {
        self.textured
    }

    /// Mean linear albedo, without texture.
    pub fn albedo(&self) -> [f64; 3] {
        self.albedo
    }

    /// The values drawn for this sample.
    pub fn drawn(&self) -> MaterialDraw {
        MaterialDraw {
            texture_offset: self.offset.to_array(),
            pith_distance: self.pith.0 * self.material.scale,
            brightness: self.brightness,
        }
    }

    /// The surface at `p`, on a piece whose grain is `grain`.
    pub fn surface(&self, p: &SurfacePoint, grain: &Grain) -> Surface {
        if !self.textured() {
            return self.untextured();
        }
        let texture = self.texture_point(p);
        let footprint = p.footprint / self.material.scale;
        let ladder = Ladder::new(&self.noise, texture, footprint);
        self.textured_surface(p, grain, Rungs::Own(&ladder))
    }

    /// The surfaces at up to four points `points` seen side by side (neighbouring pixels of
    /// a row) on one piece, whose grain is `grain`, into `out`: what `surface` gives at each,
    /// to the bit, with the fractal fields of all the points evaluated together (see
    /// `SpanLadder`).
    pub fn surfaces(&self, points: &[SurfacePoint], grain: &Grain, out: &mut [Surface]) {
        assert!(points.len() <= LANES && out.len() == points.len());
        if !self.textured() || points.len() < 2 {
            for (s, p) in out.iter_mut().zip(points) {
                *s = self.surface(p, grain);
            }
            return;
        }
        let n = points.len();
        let texture: [DVec3; LANES] =
            std::array::from_fn(|k| self.texture_point(&points[k.min(n - 1)]));
        let footprints: [f64; LANES] =
            std::array::from_fn(|k| points[k.min(n - 1)].footprint / self.material.scale);
        let span = SpanLadder::new(&self.noise, &texture[..n], &footprints[..n]);
        for (k, (s, p)) in out.iter_mut().zip(points).enumerate() {
            *s = self.textured_surface(p, grain, Rungs::Span(&span, k));
        }
    }

    /// Where the material's texture is read for `p`: offset by the sample's cut, in units of
    /// the material's scale.
    fn texture_point(&self, p: &SurfacePoint) -> DVec3 {
        (p.rest + self.offset) / self.material.scale
    }

    /// The surface of a textured material at `p`, its fractal fields read from `rungs`.
    fn textured_surface(&self, p: &SurfacePoint, grain: &Grain, rungs: Rungs) -> Surface {
        let m = &self.material;
        let base = self.albedo;
        let mut s = self.untextured();
        let at = Point {
            p: self.texture_point(p),
            rungs,
            rest: p.rest,
            normal: p.rest_normal,
            footprint: p.footprint / m.scale,
            grain,
            shader: self,
            streaks: std::cell::Cell::new(None),
        };
        s.albedo = match &m.texture {
            Texture::Image { pixels, size, .. } => {
                triplanar(pixels, &at, *size / m.scale).map(|c| c * self.brightness)
            }
            Texture::Procedural => at.base(m.base, base),
        };
        // `matches!`, not `==`: comparing the enum compares an image's strings at every point.
        if matches!(m.texture, Texture::Procedural) {
            at.exposure(&mut s);
        }
        let calm = m
            .conditions
            .iter()
            .find(|c| c.kind == ConditionKind::New)
            .map_or(1.0, |c| 1.0 - 0.7 * c.intensity);
        if calm < 1.0 {
            s.albedo = mix(base, s.albedo, calm);
        }
        for c in &m.conditions {
            at.condition(*c, &mut s);
        }
        s
    }

    /// Whether `p` lies on a crack (cheaper than `surface` when only the mask is wanted).
    pub fn crack(&self, p: &SurfacePoint, grain: &Grain) -> bool {
        let m = &self.material;
        m.conditions
            .iter()
            .filter(|c| c.kind == ConditionKind::Cracked)
            .any(|c| {
                let q = (p.rest + self.offset) / m.scale;
                let (_, on) = self.cracks(q, c.intensity, p.footprint / m.scale, grain);
                on
            })
    }

    /// Crack network: borders between Voronoi cells (distorted so they wander), only some of
    /// them open, each with its own width. Timber splits along its grain, so there the cells
    /// are drawn out eight times along it. Returns the fraction of the pixel the crack covers,
    /// and whether that is enough to label the pixel a crack: a fifth or more, i.e. the pixel is
    /// visibly darker (cracks much thinner than a pixel are invisible, and stay unlabelled).
    fn cracks(&self, q: DVec3, intensity: f64, footprint: f64, grain: &Grain) -> (f64, bool) {
        let timber = matches!(self.material.base, Base::Timber(_));
        // Checks open along the grain as the wood dries: cells drawn out six times along it
        // give splits 10–50 cm long.
        let q = if timber {
            q - grain.axis * (q.dot(grain.axis) * 5.0 / 6.0)
        } else {
            q
        };
        let size = 0.3 / (0.6 + intensity) * if timber { 0.5 } else { 1.0 };
        let wander = DVec3::from_array(self.noise.fractals::<3>(q, 0.15, 3, footprint));
        let c = self.noise.cells(q + 0.25 * size * wander, size);
        let edge = pair(c.id, c.neighbour);
        if unit(edge, 7) > 0.3 + 0.5 * intensity {
            return (0.0, false);
        }
        // Concrete cracks are 0.4–3 mm wide; drying checks in timber 2–6 mm at the surface.
        let width = if timber {
            (1.5e-3 + 4e-3 * intensity) * (0.5 + unit(edge, 8))
        } else {
            (0.4e-3 + 2.5e-3 * intensity) * (0.4 + 1.2 * unit(edge, 8))
        };
        let covered = ((0.5 * (width + footprint) - c.border) / footprint).clamp(0.0, 1.0)
            * (width / footprint).min(1.0);
        (covered, covered >= CRACK_LABEL_COVER)
    }
}

/// A surface point in texture space, with what the generators need around it.
struct Point<'a> {
    /// Texture-space position (offset, divided by the material scale).
    p: DVec3,
    /// The octaves of the material's fractal fields at `p`.
    rungs: Rungs<'a>,
    rest: DVec3,
    normal: DVec3,
    footprint: f64,
    grain: &'a Grain,
    shader: &'a Shader,
    /// The vertical streak noise, once a pattern has asked for it.
    streaks: std::cell::Cell<Option<[f64; 4]>>,
}

/// Where a point reads the octaves of its fractal fields: its own ladder, or point `k` of a
/// span's.
#[derive(Clone, Copy)]
enum Rungs<'a> {
    Own(&'a Ladder<'a>),
    Span(&'a SpanLadder<'a>, usize),
}

/// What the sheet courses of a shell give a point.
struct Courses {
    /// Share of the pixel a seam covers.
    seam: f64,
    /// Relative tone of the point's sheet course (within ±6 %).
    tone: f64,
    /// Distance below the ring seam above, texture metres (water runs from it).
    below_ring: f64,
}

/// How much of a run is left `d` metres below its source: a half at `RUN_LENGTH`.
fn fade_below(d: f64) -> f64 {
    let x = d / RUN_LENGTH;
    1.0 / (1.0 + x * x)
}

/// Distance from `x` to the nearest multiple of `period`.
fn to_joint(x: f64, period: f64) -> f64 {
    let f = x.rem_euclid(period);
    f.min(period - f)
}

impl Point<'_> {
    /// A fractal field at this point.
    fn field(&self, field: Field) -> f64 {
        match self.rungs {
            Rungs::Own(ladder) => ladder.get(field),
            Rungs::Span(span, k) => span.get(k, field),
        }
    }

    /// The base material's albedo (linear) at this point; `colour` is its mean.
    fn base(&self, base: Base, colour: [f64; 3]) -> [f64; 3] {
        match base {
            Base::Plain => colour,
            Base::Steel => {
                // Mill scale, the blue-grey oxide skin of hot rolling (the base colour); where
                // it is thin or has flaked — where rust starts first, low in the same field —
                // the paler grey steel shows.
                let mottle = self.field(STEEL_MOTTLE);
                let fine = self.field(BASE_FINE);
                let flaked = smoothstep(0.15, 0.35, -mottle - 0.4 * fine);
                scale(
                    colour,
                    (1.0 + 0.08 * mottle + 0.06 * fine) * (1.0 + 0.22 * flaked),
                )
            }
            Base::GalvanisedSteel => {
                // Spangle: zinc crystals a centimetre across, each with its own sheen. Within
                // half a pixel of a grain boundary the two crystals' sheens blend, equally on
                // the boundary itself, so the albedo is continuous across it and the boundary
                // is anti-aliased.
                let c = self.shader.noise.cells(self.p, 0.012);
                let own = (0.5 + c.border / self.footprint).min(1.0);
                let sheen = own * unit(c.id, 3) + (1.0 - own) * unit(c.neighbour, 3);
                let crystal = 0.12 * (sheen - 0.5) * self.resolved(0.012);
                scale(colour, 1.0 + crystal + 0.08 * self.field(SHEEN))
            }
            Base::WeatheringSteel => {
                let patina = smoothstep(-0.4, 0.5, self.field(PATINA));
                mix(colour, PALETTE.rust_dark, patina * 0.6)
            }
            Base::Aluminium => scale(colour, 1.0 + 0.06 * self.brushed(0.002)),
            Base::Concrete => {
                let pores = self.pores(0.008, 0.0012, 0.3);
                scale(
                    colour,
                    (1.0 + 0.1 * self.field(CONCRETE_MOTTLE) + 0.05 * self.field(CONCRETE_FINE))
                        * (1.0 - 0.55 * pores)
                        * self.formwork(),
                )
            }
            Base::Timber(species) => self.wood(species, colour),
            Base::Plastic => scale(colour, 1.0 + 0.02 * self.field(SMOOTH)),
            Base::Brick => self.brick(colour),
            Base::Stone => self.stone(colour),
            Base::Painted => scale(colour, 1.0 + 0.03 * self.field(PAINT)),
            Base::Ground => scale(
                colour,
                1.0 + 0.18 * self.field(CONCRETE_MOTTLE) + 0.1 * self.field(CONCRETE_FINE),
            ),
        }
    }

    /// Share of the pixel a line `width` wide covers, `d` from its centre line.
    fn line(&self, d: f64, width: f64) -> f64 {
        ((0.5 * width - d) / self.footprint + 0.5).clamp(0.0, 1.0)
            * (width / self.footprint).min(1.0)
    }

    /// Share of the pixel a round hole of `radius` covers, `d` from its centre.
    fn disk(&self, d: f64, radius: f64) -> f64 {
        ((radius - d) / self.footprint + 0.5).clamp(0.0, 1.0)
            * (radius / self.footprint).min(1.0).powi(2)
    }

    /// Streaks that run down the surface: noise stretched 20× vertically (features about
    /// 3 cm across and 60 cm long, two octaves), four independent lanes from one lattice evaluation,
    /// each roughly in [−1, 1]. Evaluated once per point, whoever asks first.
    fn streaks(&self) -> [f64; 4] {
        if let Some(v) = self.streaks.get() {
            return v;
        }
        let q = DVec3::new(self.p.x / 0.03, self.p.y / 0.03, self.p.z / 0.6);
        let v = self
            .shader
            .noise
            .fractals::<4>(q, 1.0, 1, self.footprint / 0.03);
        self.streaks.set(Some(v));
        v
    }

    /// Distance below the top of the piece, texture metres.
    fn below_top(&self) -> f64 {
        ((self.grain.top - self.rest.z) / self.shader.material.scale).max(0.0)
    }

    /// Sheet courses of a large vertical shell (a silo's or tank's wall): ring seams every
    /// `COURSE_HEIGHT` up from the piece's bottom, vertical seams between the sheets of a
    /// ring, and a slightly different tone per course (plates from different heats). Pieces
    /// lying down, and slender ones (legs, under 0.4 m from their axis), have none.
    fn courses(&self) -> Option<Courses> {
        let g = self.grain;
        if g.axis.z.abs() < 0.9 {
            return None;
        }
        let scale_m = self.shader.material.scale;
        let off_axis = self.rest - g.centre;
        let radial = off_axis - off_axis.dot(g.axis) * g.axis;
        let radius = radial.length();
        let weight = smoothstep(0.4, 0.8, radius);
        if weight == 0.0 {
            return None;
        }
        let u = (self.rest.z - g.bottom) / scale_m / COURSE_HEIGHT;
        let course = u.floor();
        let to_lower = (u - course) * COURSE_HEIGHT;
        let to_upper = COURSE_HEIGHT - to_lower;
        let sheet = std::f64::consts::TAU / SHEETS_PER_RING;
        let stagger = if course.rem_euclid(2.0) == 1.0 {
            0.5
        } else {
            0.0
        };
        let around = libm::atan2(radial.y, radial.x) / sheet + stagger;
        let vertical = to_joint(around, 1.0) * sheet * radius / scale_m;
        let seam = weight * self.line(to_lower.min(to_upper).min(vertical), SEAM_WIDTH);
        // Tones blend over the seam (or a pixel) around each ring, equally on the ring, so
        // the albedo stays continuous across it.
        let salt = self.shader.offset.x.to_bits();
        let tone_of = |k: f64| 0.12 * (unit(pair(k as i64 as u64, salt), 11) - 0.5);
        #[expect(
            clippy::manual_clamp,
            reason = "max then min sends a NaN footprint to SEAM_WIDTH, where clamp keeps the NaN"
        )]
        let blend = self.footprint.max(SEAM_WIDTH).min(0.25 * COURSE_HEIGHT);
        let down = 0.5 * (1.0 - to_lower / blend).clamp(0.0, 1.0);
        let up = 0.5 * (1.0 - to_upper / blend).clamp(0.0, 1.0);
        let tone = (1.0 - down - up) * tone_of(course)
            + down * tone_of(course - 1.0)
            + up * tone_of(course + 1.0);
        Some(Courses {
            seam,
            tone: weight * tone,
            below_ring: to_upper,
        })
    }

    /// Formwork marks on cast concrete, as a factor on the albedo: grout lines at the joints
    /// between panels (across the piece, every `FORM_PANEL` along its grain) and, on pieces
    /// lying down, the holes of the form ties: `TIE_SPACING` apart along the piece, half a
    /// spacing from the joints, in rows at mid-height and every spacing above and below.
    fn formwork(&self) -> f64 {
        let along = self.p.dot(self.grain.axis);
        let joint = self.line(to_joint(along, FORM_PANEL), FORM_JOINT);
        let tie = if self.grain.axis.z.abs() < 0.5 {
            let da = to_joint(along + 0.5 * TIE_SPACING, TIE_SPACING);
            let height = (self.rest.z - self.grain.centre.z) / self.shader.material.scale;
            let dz = to_joint(height, TIE_SPACING);
            self.disk((da * da + dz * dz).sqrt(), TIE_RADIUS)
        } else {
            0.0
        };
        (1.0 - 0.45 * joint) * (1.0 - 0.7 * tie)
    }

    /// The intensity of condition `kind` (0 without it).
    fn intensity(&self, kind: ConditionKind) -> f64 {
        self.shader
            .material
            .conditions
            .iter()
            .filter(|c| c.kind == kind)
            .map(|c| c.intensity)
            .fold(0.0, f64::max)
    }

    /// What standing outdoors does to steel, paint and concrete before any named condition:
    /// the seams and courses of a sheeted shell; water running down from the top edge and
    /// from ring seams, carrying dirt (darker streaks); on paint, chalking (paler, matte
    /// where the binder has weathered) and dirt splashed up near the piece's bottom; on
    /// concrete, dark water stains and, when stained or weathered, white efflorescence.
    /// "new" keeps a surface clean.
    fn exposure(&self, s: &mut Surface) {
        let base = self.shader.material.base;
        if !matches!(base, Base::Steel | Base::Painted | Base::Concrete) {
            return;
        }
        let clean = 1.0 - self.intensity(ConditionKind::New);
        let weathered = self.intensity(ConditionKind::Weathered);
        let stained = self.intensity(ConditionKind::Stained);
        let mut below = self.below_top();
        if base != Base::Concrete
            && let Some(c) = self.courses()
        {
            s.albedo = scale(s.albedo, (1.0 + c.tone) * (1.0 - 0.6 * c.seam));
            below = below.min(c.below_ring);
        }
        if clean <= 0.0 {
            return;
        }
        // Bare steel weathers by rusting (the rust condition's runs); paint and concrete
        // collect dirt where water runs.
        if base == Base::Steel {
            return;
        }
        let streak = self.streaks();
        let runs = smoothstep(0.05, 0.5, streak[0]) * fade_below(below) * clean;
        match base {
            Base::Painted => {
                let age = (PAINT_AGE + 0.65 * weathered) * clean;
                // Chalking is broad and even, a little stronger in places.
                let chalk = age * (0.6 + 0.4 * smoothstep(-0.5, 0.5, self.field(CHALK)));
                s.albedo = mix(s.albedo, PALETTE.chalk, 0.08 * chalk);
                s.roughness = lerp(s.roughness, 1.0, chalk);
                s.specular = lerp(s.specular, 0.02, chalk);
                let scale_m = self.shader.material.scale;
                let height = (self.grain.top - self.grain.bottom) / scale_m;
                let above_bottom = (self.rest.z - self.grain.bottom) / scale_m;
                let band = (0.25 * height).clamp(1e-3, 1.0);
                let splash = (1.0 - above_bottom / band).clamp(0.0, 1.0);
                let dirt = age * splash * splash * (0.7 + 0.3 * self.field(GRIME));
                s.albedo = scale(s.albedo, (1.0 - 0.45 * dirt) * (1.0 - 0.35 * age * runs));
            }
            _ => {
                s.albedo = scale(s.albedo, 1.0 - (0.15 + 0.3 * stained) * runs);
                let deposit = (stained + weathered).min(1.0);
                if deposit > 0.0 {
                    let white = smoothstep(0.1, 0.6, streak[2]) * fade_below(below);
                    s.albedo = mix(s.albedo, PALETTE.efflorescence, 0.6 * deposit * white);
                }
            }
        }
    }

    /// How visible a feature of `size` metres is: 1 when it spans several pixels, 0 when it
    /// is smaller than one.
    fn resolved(&self, size: f64) -> f64 {
        (size / self.footprint - 1.0).clamp(0.0, 1.0)
    }

    /// Noise stretched along the grain: long fine streaks (brushed metal, wood fibres).
    fn brushed(&self, width: f64) -> f64 {
        let along = self.p.dot(self.grain.axis);
        let across = self.p - along * self.grain.axis;
        let stretched = across + self.grain.axis * (along * 0.02);
        self.shader
            .noise
            .fractal(stretched, width * 4.0, 3, self.footprint)
    }

    /// Fraction of the point darkened by pores: small round holes in some cells.
    fn pores(&self, cell: f64, radius: f64, share: f64) -> f64 {
        let c = self.shader.noise.cells(self.p, cell);
        if unit(c.id, 4) > share {
            return 0.0;
        }
        self.disk(c.f1, radius * (0.3 + unit(c.id, 5)))
    }

    /// Growth rings around a pith running along the grain, a little outside the piece (as in
    /// a flat-sawn board), with early/late wood contrast, ring wander and fibres.
    fn wood(&self, species: Species, colour: [f64; 3]) -> [f64; 3] {
        let (spacing, contrast) = match species {
            Species::Pine => (0.004, 0.35),
            Species::Spruce => (0.003, 0.25),
            Species::Oak => (0.0025, 0.3),
            Species::Ash => (0.0025, 0.3),
            Species::Birch => (0.002, 0.15),
            Species::Cedar => (0.0025, 0.3),
            Species::Teak => (0.003, 0.25),
            Species::Walnut => (0.003, 0.3),
            Species::Mahogany => (0.004, 0.2),
            Species::Rosewood => (0.0015, 0.45),
        };
        let scale_m = self.shader.material.scale;
        let axis = self.grain.axis;
        let (e1, e2) = axis.any_orthonormal_pair();
        let (distance, [cos, sin]) = self.shader.pith;
        let pith = self.grain.centre + distance * (cos * e1 + sin * e2);
        let radial = (self.rest - pith) - (self.rest - pith).dot(axis) * axis;
        let r = radial.length() / scale_m + 0.004 * self.field(RING_WANDER);
        let ring = (r / spacing).fract();
        // Late wood: the dark band at the end of each year's growth.
        let late = smoothstep(0.6, 0.9, ring) * (1.0 - smoothstep(0.95, 1.0, ring));
        let visible = self.resolved(spacing);
        // Seen from afar, rings merge into the figure: bands where growth was slower, a few
        // centimetres wide and long along the grain (the arches of a flat-sawn board).
        let along = self.rest.dot(axis) / scale_m;
        let figure = self
            .shader
            .noise
            .gradient(DVec3::new(r / (6.0 * spacing), along / 0.8, 0.0), 1.0);
        let darkening = contrast * ((late - 0.3) * visible + 0.5 * figure);
        let fibres = 0.06 * self.brushed(0.0008);
        scale(colour, 1.0 - darkening + fibres)
    }

    /// Running-bond brickwork: 215 × 65 mm bricks with 10 mm mortar joints in horizontal
    /// courses. The bond is solid (a function of position, like every pattern here), so it
    /// turns corners without a seam: bed joints are levels of z, head joints levels of x + y,
    /// which runs along any wall face except one at exactly 45° to the axes.
    fn brick(&self, colour: [f64; 3]) -> [f64; 3] {
        let (u, v) = (self.p.x + self.p.y, self.p.z);
        let (length, height, joint) = (0.225, 0.075, 0.01);
        let course = (v / height).floor();
        let shifted = u + if course.rem_euclid(2.0) == 1.0 {
            0.5 * length
        } else {
            0.0
        };
        let column = (shifted / length).floor();
        let d = to_joint(shifted, length).min(to_joint(v, height));
        let mortar = self.line(d, joint);
        let id = pair(course as i64 as u64, column as i64 as u64);
        let brick = scale(
            colour,
            1.0 + 0.24 * (unit(id, 6) - 0.5) + 0.06 * self.field(SMOOTH),
        );
        mix(brick, PALETTE.mortar, mortar)
    }

    /// Random-rubble stone: Voronoi blocks about 0.3 m across, each its own shade, with joints.
    fn stone(&self, colour: [f64; 3]) -> [f64; 3] {
        let c = self.shader.noise.cells(self.p, 0.3);
        let mortar = self.line(c.border, 0.006);
        let block = scale(
            colour,
            1.0 + 0.3 * (unit(c.id, 9) - 0.5) + 0.08 * self.field(STONE),
        );
        mix(block, scale(PALETTE.mortar, 0.7), mortar)
    }

    fn condition(&self, c: Condition, s: &mut Surface) {
        let i = c.intensity;
        match c.kind {
            ConditionKind::Rusty | ConditionKind::Corroded => {
                let corroded = c.kind == ConditionKind::Corroded;
                let reach = if corroded { 0.85 * i + 0.15 } else { i };
                // Patches cover about `reach` of the surface and have
                // ragged edges: fine noise shifts the threshold locally.
                let field = self.field(RUST) + 0.35 * self.field(RUST_EDGE);
                let margin = coverage_threshold(reach) - field;
                let patch = smoothstep(-0.3, 0.25, margin);
                // Young rust is orange-brown, old compact rust dark brown; whole patches lean
                // one way (the broad field), spots within them the other.
                let age = smoothstep(
                    -0.6,
                    0.6,
                    0.7 * self.field(RUST_TONE) + 0.8 * self.field(RUST_AGE),
                );
                let mut rust = if age < 0.5 {
                    mix(PALETTE.rust_light, PALETTE.rust_mid, 2.0 * age)
                } else {
                    mix(PALETTE.rust_mid, PALETTE.rust_dark, 2.0 * age - 1.0)
                };
                // Pitting: small dark pits in the rust, more the deeper the attack. Peaks of
                // fine noise, so pits finer than a pixel fade with their octaves.
                let pits = smoothstep(0.55 - 0.2 * reach, 0.75 - 0.2 * reach, self.field(PITS));
                rust = scale(rust, 1.0 - 0.55 * pits);
                if corroded {
                    rust = scale(rust, 1.0 - 0.6 * self.pores(0.004, 0.0015, 0.6));
                }
                let metal = self.shader.material.is_metal();
                let opacity = if metal { 1.0 } else { 0.6 };
                if self.shader.material.base == Base::Painted {
                    // Where the coating fails, rust creeps under it: a rim of blistered,
                    // lifted paint, paler, just outside each patch.
                    let rim = smoothstep(-0.4, -0.2, margin) * (1.0 - patch);
                    s.albedo = scale(s.albedo, 1.0 + 0.3 * rim);
                }
                // Outside the patches, a brown bloom dulls the surface, and rust washed out
                // of the top edge and the patches above runs down in streaks.
                let bloom = 0.55 * reach * smoothstep(-0.6, 0.2, -field);
                let runs = if patch < 1.0 {
                    reach * smoothstep(0.0, 0.45, self.streaks()[1]) * fade_below(self.below_top())
                } else {
                    0.0
                };
                let cover = (patch + (1.0 - patch) * (bloom + 0.8 * runs).min(1.0)) * opacity;
                s.albedo = mix(s.albedo, rust, cover);
                s.roughness = lerp(s.roughness, 0.95, cover);
                s.specular = lerp(s.specular, 0.03, cover);
            }
            ConditionKind::Cracked => {
                let footprint = self.footprint.max(f64::MIN_POSITIVE);
                let (covered, on) = self.shader.cracks(self.p, i, footprint, self.grain);
                s.albedo = mix(s.albedo, scale(s.albedo, 0.08), covered);
                s.crack |= on;
            }
            ConditionKind::Weathered => {
                let grey = luminance(s.albedo);
                let blotch = 1.0 + 0.18 * i * self.field(BLOTCH);
                s.albedo = scale(mix(s.albedo, [grey * 1.1; 3], 0.45 * i), blotch);
                s.roughness = lerp(s.roughness, 1.0, 0.5 * i);
            }
            ConditionKind::Stained => {
                // Streaks run down the whole face (the noise stretched 20× vertically).
                let streak = smoothstep(0.1, 0.5, self.streaks()[3] + i - 0.6);
                s.albedo = scale(s.albedo, 1.0 - 0.45 * streak * i.sqrt());
            }
            ConditionKind::Mossy => {
                let upward = 0.35 * self.normal.z;
                let patch = smoothstep(
                    -0.05,
                    0.05,
                    self.field(MOSS_PATCH) + upward + 0.8 * i - 0.75,
                );
                let moss = scale(PALETTE.moss, 1.0 + 0.3 * self.field(MOSS_TONE));
                s.albedo = mix(s.albedo, moss, patch);
                s.roughness = lerp(s.roughness, 1.0, patch);
                s.specular = lerp(s.specular, 0.02, patch);
            }
            ConditionKind::New => {
                s.roughness *= 1.0 - 0.3 * i;
                s.specular = (s.specular * (1.0 + 0.3 * i)).min(1.0);
            }
            ConditionKind::Wet => {
                // A water film darkens porous surfaces and adds a glossy layer (F0 ≈ 0.02).
                s.albedo = s
                    .albedo
                    .map(|c| libm::pow(c, 1.0 + 0.6 * i) * (1.0 - 0.25 * i));
                s.roughness *= 1.0 - 0.7 * i;
                s.specular = s.specular.max(0.02 + 0.03 * i);
            }
            ConditionKind::Worn => {
                // Paint wears through on about half the share rust of the same intensity covers.
                let field = self.field(WEAR);
                let patch = smoothstep(-0.05, 0.05, coverage_threshold(0.5 * i) - field);
                let bare = mix(
                    PALETTE.bare_steel,
                    PALETTE.rust_dark,
                    0.5 * smoothstep(-0.3, 0.3, self.field(WORN_SUBSTRATE)),
                );
                s.albedo = mix(s.albedo, bare, patch);
                s.roughness = lerp(s.roughness, 0.8, patch);
            }
        }
    }
}

/// The level below which fractal noise lies on about `share` of the surface (the noise is
/// roughly normal with a standard deviation near 0.35; linear in the middle is close enough).
fn coverage_threshold(share: f64) -> f64 {
    0.7 * (share - 0.5)
}

/// An image texture projected along the three axes of the undeformed structure and blended
/// by the rest normal (sharply, so flat faces show one projection).
fn triplanar(image: &super::image::TextureImage, at: &Point, size: f64) -> [f64; 3] {
    let n = at.normal.abs();
    let weights = [n.x.powi(4), n.y.powi(4), n.z.powi(4)];
    let total: f64 = weights.iter().sum();
    let p = at.p / size;
    let texel = at.footprint / size;
    // Image v runs downwards; world z runs up.
    let planes = [(p.y, -p.z), (p.x, -p.z), (p.x, -p.y)];
    let mut sum = [0.0; 3];
    for (w, (u, v)) in weights.iter().zip(planes) {
        if *w > 1e-4 * total {
            let c = image.sample(u, v, texel);
            sum = std::array::from_fn(|k| sum[k] + w / total * c[k]);
        }
    }
    sum
}

/// An sRGB colour in linear light.
fn linear(srgb: [f64; 3]) -> [f64; 3] {
    srgb.map(super::srgb_to_linear)
}

fn mix(a: [f64; 3], b: [f64; 3], t: f64) -> [f64; 3] {
    std::array::from_fn(|k| lerp(a[k], b[k], t))
}

fn lerp(a: f64, b: f64, t: f64) -> f64 {
    a + (b - a) * t
}

fn scale(c: [f64; 3], f: f64) -> [f64; 3] {
    c.map(|x| (x * f).clamp(0.0, 1.0))
}

/// Relative luminance of a linear colour (Rec. 709 weights).
pub fn luminance(c: [f64; 3]) -> f64 {
    0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::materials::prompt::compile;
    use crate::seeds::Scope;

    fn shader(prompt: &str) -> Shader {
        let material = compile(prompt, true).unwrap().material;
        Shader::new(&material, &mut Stream::new(3, Scope::Sample(0), "material"))
    }

    const GRAIN: Grain = Grain {
        axis: DVec3::X,
        centre: DVec3::ZERO,
        bottom: 0.0,
        top: 2.0,
    };

    /// Points spread over a 2 m × 2 m wall facing −y.
    fn wall(n: usize) -> impl Iterator<Item = SurfacePoint> {
        (0..n).map(move |i| {
            let t = i as f64;
            SurfacePoint {
                rest: DVec3::new(
                    2.0 * (t * 0.618_034).fract(),
                    0.0,
                    2.0 * (t * 0.414_214).fract(),
                ),
                rest_normal: -DVec3::Y,
                footprint: 1e-4,
            }
        })
    }

    fn is_rust(c: [f64; 3]) -> bool {
        // Rust is clearly red-brown; steel is grey with a touch of blue.
        c[0] > 1.5 * c[2]
    }

    #[test]
    fn rust_covers_a_share_of_the_surface_that_grows_with_intensity() {
        let shares: Vec<f64> = ["slightly rusty steel", "rusty steel", "heavily rusty steel"]
            .iter()
            .map(|p| {
                let s = shader(p);
                let n = 4000;
                wall(n)
                    .filter(|q| is_rust(s.surface(q, &GRAIN).albedo))
                    .count() as f64
                    / n as f64
            })
            .collect();
        // Intensities 0.3, 0.6 and 1.0: the share of rust follows them within ±0.2.
        for (share, intensity) in shares.iter().zip([0.3, 0.6, 1.0]) {
            assert!((share - intensity).abs() < 0.2, "{shares:?}");
        }
        assert!(shares[0] < shares[1] && shares[1] < shares[2], "{shares:?}");
        assert!(wall(4000).all(|q| !is_rust(shader("steel").surface(&q, &GRAIN).albedo)));
    }

    #[test]
    fn a_span_of_points_gets_each_points_own_surface_to_the_bit() {
        // Rows of one to four neighbouring pixels (1 mm apart, as at a few metres; footprints
        // growing along the row, as on a receding face; from 0.1 mm, where every octave shows,
        // to 5 cm, where most have faded) and scattered points, on materials that read every
        // lane of both lane groups of the octave ladder.
        for prompt in [
            "A photo of rusty steel beam for construction",
            "A photo of plastic board for construction",
            "A photo of cracked timber for construction",
            "weathered mossy stained concrete",
            "worn blue paint",
            "galvanised steel",
            "brick",
        ] {
            let s = shader(prompt);
            let scattered: Vec<SurfacePoint> = wall(24).collect();
            for (i, start) in wall(60).enumerate() {
                let n = 1 + i % 4;
                let footprint = 1e-4 * 2f64.powi(i as i32 % 10);
                let row: Vec<SurfacePoint> = (0..n)
                    .map(|k| SurfacePoint {
                        rest: start.rest + DVec3::new(1e-3 * k as f64, 0.0, 0.0),
                        footprint: footprint * (1.0 + 0.1 * k as f64),
                        ..start
                    })
                    .collect();
                let chunk = i % 6 * 4;
                for points in [&row[..], &scattered[chunk..chunk + n]] {
                    let mut together = vec![s.untextured(); n];
                    s.surfaces(points, &GRAIN, &mut together);
                    for (p, got) in points.iter().zip(&together) {
                        assert_eq!(*got, s.surface(p, &GRAIN), "{prompt} at {p:?}");
                    }
                }
            }
        }
    }

    #[test]
    fn every_material_is_continuous_in_the_rest_position() {
        // Across an edge two triangles evaluate the same function at the same point, so
        // continuity of the function is continuity across edges. With a pixel footprint of
        // 1 mm, a 1 µm step may change the albedo by at most about a thousandth.
        for prompt in [
            "rusty steel",
            "heavily corroded steel",
            "cracked concrete",
            "galvanised steel",
            "rosewood",
            "cracked timber",
            "brick",
            "stone",
            "worn blue paint",
            "mossy stained concrete",
        ] {
            let s = shader(prompt);
            for q in wall(500) {
                let q = SurfacePoint {
                    footprint: 1e-3,
                    ..q
                };
                let near = SurfacePoint {
                    rest: q.rest + DVec3::new(1e-6, 0.0, 0.7e-6),
                    ..q
                };
                let (a, b) = (s.surface(&q, &GRAIN), s.surface(&near, &GRAIN));
                for k in 0..3 {
                    assert!(
                        (a.albedo[k] - b.albedo[k]).abs() < 5e-3,
                        "{prompt}: {a:?} vs {b:?} at {}",
                        q.rest
                    );
                }
            }
        }
    }

    #[test]
    fn texture_seen_from_afar_averages_instead_of_aliasing() {
        // A pixel 1 m wide on concrete spans every feature of it: each sample must lie near
        // the mean of the fine texture, not on a random grain of it.
        let s = shader("concrete");
        let fine: Vec<f64> = wall(4000)
            .map(|q| luminance(s.surface(&q, &GRAIN).albedo))
            .collect();
        let mean = fine.iter().sum::<f64>() / fine.len() as f64;
        let spread =
            |v: &[f64]| (v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / v.len() as f64).sqrt();
        let far: Vec<f64> = wall(4000)
            .map(|q| {
                let q = SurfacePoint {
                    footprint: 1.0,
                    ..q
                };
                luminance(s.surface(&q, &GRAIN).albedo)
            })
            .collect();
        assert!(
            spread(&far) < 0.5 * spread(&fine),
            "{} vs {}",
            spread(&far),
            spread(&fine)
        );
        let far_mean = far.iter().sum::<f64>() / far.len() as f64;
        assert!((far_mean - mean).abs() < 0.1 * mean, "{far_mean} vs {mean}");
    }

    #[test]
    fn cracks_grow_with_intensity_and_the_mask_matches_the_image() {
        let share = |prompt: &str| {
            let s = shader(prompt);
            let mut cracked = 0;
            for q in wall(20_000) {
                let on = s.crack(&q, &GRAIN);
                assert_eq!(on, s.surface(&q, &GRAIN).crack);
                cracked += usize::from(on);
            }
            cracked as f64 / 20_000.0
        };
        let (light, heavy) = (
            share("slightly cracked concrete"),
            share("heavily cracked concrete"),
        );
        assert!(light > 0.0 && heavy > 2.0 * light, "{light} {heavy}");
        assert_eq!(share("concrete"), 0.0);
    }

    #[test]
    fn timber_grain_runs_along_the_piece() {
        // Along the grain the colour changes slowly; across it, ring after ring.
        let s = shader("oak");
        let variation = |step: DVec3| {
            (0..400)
                .map(|i| {
                    let at = |k: f64| SurfacePoint {
                        rest: DVec3::new(0.3, -0.05, 0.2) + step * (f64::from(i) + k),
                        rest_normal: -DVec3::Y,
                        footprint: 1e-4,
                    };
                    let (a, b) = (s.surface(&at(0.0), &GRAIN), s.surface(&at(1.0), &GRAIN));
                    (luminance(a.albedo) - luminance(b.albedo)).abs()
                })
                .sum::<f64>()
        };
        let (along, across) = (variation(DVec3::X * 5e-4), variation(DVec3::Z * 5e-4));
        assert!(across > 3.0 * along, "along {along}, across {across}");
    }

    #[test]
    fn brick_joints_fall_on_the_bond() {
        // 65 mm bricks + 10 mm joints: 75 mm courses. Half-way between bed joints is brick,
        // on a bed joint is mortar, whatever the sample's texture offset.
        let s = shader("brick");
        let mortar = PALETTE.mortar;
        let shift = s.offset.z;
        for course in 0..20 {
            let joint = 0.075 * f64::from(course) - shift.rem_euclid(0.075);
            let at = |z: f64| SurfacePoint {
                rest: DVec3::new(0.37, 0.0, z),
                rest_normal: -DVec3::Y,
                footprint: 1e-4,
            };
            let differs =
                |c: [f64; 3]| (0..3).map(|k| (c[k] - mortar[k]).abs()).fold(0.0, f64::max);
            assert!(differs(s.surface(&at(joint), &GRAIN).albedo) < 1e-12);
            assert!(differs(s.surface(&at(joint + 0.0375), &GRAIN).albedo) > 0.01);
        }
    }

    #[test]
    fn each_sample_cuts_its_own_texture_and_plain_colours_stay_plain() {
        let material = compile("rusty steel", true).unwrap().material;
        let draw = |sample| {
            Shader::new(
                &material,
                &mut Stream::new(3, Scope::Sample(sample), "material"),
            )
        };
        let (a, again, b) = (draw(0), draw(0), draw(1));
        let points: Vec<SurfacePoint> = wall(500).collect();
        let differing = points
            .iter()
            .filter(|q| a.surface(q, &GRAIN) != b.surface(q, &GRAIN))
            .count();
        assert!(
            points
                .iter()
                .all(|q| a.surface(q, &GRAIN) == again.surface(q, &GRAIN))
        );
        assert!(differing > 250, "{differing} of 500 points differ");
        // A plain colour is the same everywhere: sRGB (0.2, 0.4, 0.6) in linear light, by the
        // sRGB standard's published decoding (0.0331, 0.1329, 0.3185).
        let plain = Shader::new(
            &Material::plain([0.2, 0.4, 0.6]),
            &mut Stream::new(3, Scope::Sample(0), "material"),
        );
        assert!(!plain.textured());
        for q in &points {
            let c = plain.surface(q, &GRAIN).albedo;
            for (got, want) in c.iter().zip([0.0331, 0.1329, 0.3185]) {
                assert!((got - want).abs() < 1e-3, "{c:?}");
            }
        }
    }
}
