//! Shading into RGB: diffuse and glossy (`gloss`) reflection of the sun, the sky, an ambient
//! term and (by default) a studio key and fill light fixed to the camera, with optional sun
//! shadows (soft over the sun's disk), sky occlusion and a ground's bounce (`daylight`); the
//! background is a colour, a sky gradient, an image or an environment map (whose SH
//! irradiance may also replace the sky's light). Linear light becomes a pixel through
//! the film's exposure and tone curve, then sRGB.
//!
//! Anti-aliasing: a first pass shades one centre ray per pixel, as for the geometric labels.
//! Where a pixel differs from a neighbour in what it sees (surface or background, or an
//! untextured shade more than one 8-bit level apart: silhouettes, creases, material
//! boundaries), it is re-shaded from four fixed sub-pixel rays averaged in linear light,
//! each untextured surface among them shaded once (at the first sub-ray that meets it) and
//! each textured face's material evaluated once, at the pixel's centre (see `edge_pixel`).
//! Texture detail is filtered by the materials themselves, so it never triggers extra rays.

use super::daylight::{DiskPattern, LightRays, Openness, environment_light, pixel_turn, sky_light};
use super::gloss::Lobe;
use super::light_cache::LightCache;
use super::trace::{GBuffer, NO_HIT, PixelSet, TraceMesh};
use super::visibility::{SecondaryRays, Visibility};
use crate::cameras::Camera;
use crate::materials::light::turn_about_z;
use crate::materials::noise::LANES;
use crate::materials::{Backdrop, Film, Lighting, Surface, srgb_to_linear};
use glam::DVec3;
use rayon::prelude::*;
use std::sync::OnceLock;

/// The surfaces of a mesh, by triangle.
pub trait Surfaces: Sync {
    /// The surface of triangle `tri` at world point `p`, seen with pixels `footprint` metres
    /// wide there.
    fn at(&self, tri: u32, p: DVec3, footprint: f64) -> Surface;
    /// `at` for each of up to four `hits` (triangle, world point, footprint) seen side by side
    /// along a row, into `out`: the same surfaces, found together where that is cheaper.
    fn at_span(&self, hits: &[(u32, DVec3, f64)], out: &mut [Surface]) {
        for (s, &(tri, p, footprint)) in out.iter_mut().zip(hits) {
            *s = self.at(tri, p, footprint);
        }
    }
    /// Untextured linear albedo of the triangle: decides where anti-aliasing is needed.
    fn flat(&self, tri: u32) -> [f64; 3];
    /// Whether the surface varies over the triangle (else `flat` is all there is to it).
    fn textured(&self, tri: u32) -> bool;
    /// Whether the triangle's surface is the same everywhere and without gloss: then under
    /// lights that cast no shadow it shows one radiance over each of its sides.
    fn matte(&self, tri: u32) -> bool;
    /// Whether, within one pixel, triangle `b` may take the surface evaluated on triangle
    /// `a`: the same material continuing over a shallow crease (facets of one curved face),
    /// not a corner between faces, where the material may differ (a top weathers unlike a
    /// side).
    fn continues(&self, a: u32, b: u32) -> bool;
}

/// A plain matte colour per triangle.
impl<F: Fn(u32) -> [f64; 3] + Sync> Surfaces for F {
    fn at(&self, tri: u32, _: DVec3, _: f64) -> Surface {
        Surface {
            albedo: self(tri),
            roughness: 1.0,
            specular: 0.0,
            crack: false,
        }
    }

    fn flat(&self, tri: u32) -> [f64; 3] {
        self(tri)
    }

    fn textured(&self, _: u32) -> bool {
        false
    }

    fn matte(&self, _: u32) -> bool {
        true
    }

    fn continues(&self, a: u32, b: u32) -> bool {
        self(a) == self(b)
    }
}

/// Sub-pixel positions for pixels on an edge: a fixed 2 × 2 grid, so the result is the same
/// on every run.
const EDGE_SAMPLES: [(f64, f64); 4] = [(0.25, 0.25), (0.75, 0.25), (0.25, 0.75), (0.75, 0.75)];

/// Light at a shading point, per channel.
struct Light {
    /// Diffuse irradiance, the sun's only where it is not shadowed.
    diffuse: [f64; 3],
    /// Diffuse irradiance as if no shadow fell.
    unshadowed: [f64; 3],
    /// Glossy reflection towards the eye.
    specular: [f64; 3],
}

/// Reflected colour of `albedo` under `diffuse` irradiance plus `specular`, through the film
/// (display-linear, 0–1).
fn reflected(film: &Film, albedo: [f64; 3], diffuse: [f64; 3], specular: [f64; 3]) -> [f64; 3] {
    std::array::from_fn(|k| film.display(albedo[k] * diffuse[k] + specular[k]))
}

/// Everything a ray needs to be shaded.
struct Shading<'a, S: Surfaces> {
    mesh: &'a TraceMesh,
    camera: &'a Camera,
    lighting: &'a Lighting,
    surfaces: &'a S,
    backdrop: &'a Backdrop,
    background: [f64; 3],
    /// Whether the backdrop is one colour (then pixels without a hit are filled, not shaded).
    plain_background: bool,
    /// The studio lights in world axes, for this view.
    studio: Option<[(DVec3, f64); 2]>,
    /// Shadow rays over the sun's disk.
    sun_disk: DiskPattern,
    /// Occlusion rays over a shaded point's hemisphere.
    hemisphere: DiskPattern,
    /// Whether the light is the same at every point of a face: lights from fixed directions
    /// without shadows, no sky, ground or environment (whose occlusion and bounce vary).
    uniform_light: bool,
    /// The camera-axes x of each column's centre ray, when the lens does not distort: x then
    /// depends on the column alone (the same bits as `ray_through`, divided once per column).
    pinhole_columns: Option<Vec<f64>>,
    /// The sample's lighting cache, or None to trace every pixel's light rays.
    cache: Option<&'a LightCache>,
}

/// What the sub-rays of one edge pixel found, by the triangle they found it on: one entry per
/// sub-ray at most.
struct FoundInPixel<T>([Option<(u32, T)>; EDGE_SAMPLES.len()]);

impl<T> Default for FoundInPixel<T> {
    fn default() -> Self {
        FoundInPixel(std::array::from_fn(|_| None))
    }
}

impl<T: Copy> FoundInPixel<T> {
    /// The value found on the first earlier triangle that `same` accepts, else `find()`'s,
    /// kept for `tri`.
    fn get_or_insert(
        &mut self,
        tri: u32,
        same: impl Fn(u32) -> bool,
        find: impl FnOnce() -> T,
    ) -> T {
        if let Some(&(_, value)) = self.0.iter().flatten().find(|(earlier, _)| same(*earlier)) {
            return value;
        }
        let value = find();
        if let Some(free) = self.0.iter_mut().find(|entry| entry.is_none()) {
            *free = Some((tri, value));
        }
        value
    }
}

/// The side of a matte triangle last shaded under uniform light, with its radiance and
/// unshadowed irradiance: consecutive pixels mostly see the same triangle, and it shows the
/// same light wherever it is met (see `Shading::uniform_side`).
#[derive(Default)]
struct LastMatte(Option<(TriangleSide, RadianceAndIrradiance)>);

/// A triangle and whether the camera sees its back.
type TriangleSide = (u32, bool);

/// A surface point's radiance and its unshadowed irradiance, as `hit_radiance` gives them.
type RadianceAndIrradiance = ([f64; 3], [f64; 3]);

/// The linear colour last encoded and its sRGB bytes: neighbouring pixels often show the
/// same colour (a matte face under uniform light), and then need no second encoding.
struct LastEncoded([f64; 3], [u8; 3]);

impl Default for LastEncoded {
    fn default() -> Self {
        // NaN equals nothing: the first colour is always encoded.
        LastEncoded([f64::NAN; 3], [0; 3])
    }
}

impl LastEncoded {
    fn encode(&mut self, linear: [f64; 3]) -> [u8; 3] {
        if linear != self.0 {
            *self = LastEncoded(linear, encode(linear));
        }
        self.1
    }
}

/// A shaded image and the rays it cast beyond each pixel's centre ray.
pub struct Shaded {
    /// sRGB, three bytes a pixel.
    pub rgb: Vec<u8>,
    /// How the anti-aliasing rays (four per edge pixel) found their surfaces; None when none
    /// were cast.
    pub edge_rays: Option<Visibility>,
    /// The rays traced through the BVH from the surfaces seen, towards the lights.
    pub secondary: Vec<SecondaryRays>,
}

/// Surfaces of the next pixels of a row, found together (`Shading::surface_ahead`).
struct SurfacesAhead {
    /// The columns they are for.
    cols: std::ops::Range<usize>,
    found: [Ahead; LANES],
}

/// A centre ray's hit on a textured surface, found ahead of its shading.
#[derive(Clone, Copy)]
struct Ahead {
    /// Point, facing normal and footprint (`hit_geometry`).
    geometry: (DVec3, DVec3, f64),
    surface: Surface,
}

impl SurfacesAhead {
    /// A placeholder surface.
    const NONE: Surface = Surface {
        albedo: [0.0; 3],
        roughness: 1.0,
        specular: 0.0,
        crack: false,
    };
}

impl Default for SurfacesAhead {
    fn default() -> Self {
        SurfacesAhead {
            cols: 0..0,
            found: [Ahead {
                geometry: (DVec3::ZERO, DVec3::ZERO, 0.0),
                surface: Self::NONE,
            }; LANES],
        }
    }
}

/// RGB8 image (sRGB) of the G-buffer, under `lighting` with the sample's lighting cache (None:
/// every pixel traces its own light rays, `shading: "per_pixel"`).
pub fn shade(
    g: &GBuffer,
    mesh: &TraceMesh,
    camera: &Camera,
    (lighting, cache): (&Lighting, Option<&LightCache>),
    surfaces: &impl Surfaces,
    backdrop: &Backdrop,
    antialias: bool,
) -> Shaded {
    let s = Shading {
        cache,
        mesh,
        camera,
        lighting,
        surfaces,
        backdrop,
        plain_background: matches!(backdrop, Backdrop::Colour(_)),
        background: match backdrop {
            Backdrop::Colour(c) => c.map(|c| srgb_to_linear(f64::from(c) / 255.0)),
            _ => [0.0; 3],
        },
        studio: lighting
            .studio
            .map(|lights| lights.map(|(d, i)| (camera.rotation * d, i))),
        sun_disk: DiskPattern::new(lighting.sun.map_or(0, |s| s.shadow_rays)),
        hemisphere: DiskPattern::new(match &lighting.environment {
            Some(e) => e.occlusion_rays,
            None => lighting.sky.map_or(0, |s| s.occlusion_rays),
        }),
        uniform_light: lighting.environment.is_none()
            && lighting.sky.is_none()
            && lighting.ground.is_none()
            && (lighting.sun.is_none() || !lighting.shadows),
        pinhole_columns: camera.intrinsics.distortion.is_none().then(|| {
            (0..camera.intrinsics.width)
                .map(|col| camera.intrinsics.ray_through_pixel(0, col).x)
                .collect()
        }),
    };
    let width = g.width as usize;
    let plain_background = s.plain_background.then(|| encode(s.background));
    // Only pixels next to a hit can be an edge, and on a plain background only hits need work.
    let spans = hit_spans(g);
    // Centre rays: the shaded colour, and (for anti-aliasing) the untextured one.
    let mut rgb = match plain_background {
        Some(bytes) => bytes.repeat(g.triangle.len()),
        None => vec![0u8; g.triangle.len() * 3],
    };
    let span = |row: usize| match plain_background {
        Some(_) => spans[row].clone(),
        None => 0..width,
    };
    let secondary = if spans.iter().all(|span| span.is_empty()) {
        Vec::new()
    } else {
        s.secondary()
    };
    if !antialias {
        rgb.par_chunks_mut(width * 3)
            .enumerate()
            .for_each(|(row, out)| s.centre_row(g, row, span(row), out, None));
        return Shaded {
            rgb,
            edge_rays: None,
            secondary,
        };
    }
    let mut edge_keys = vec![NO_SURFACE; g.triangle.len()];
    rgb.par_chunks_mut(width * 3)
        .zip(edge_keys.par_chunks_mut(width))
        .enumerate()
        .for_each(|(row, (out, keys))| s.centre_row(g, row, span(row), out, Some(keys)));
    let edge_rays = s.antialias_edges(g, &edge_keys, &spans, &mut rgb);
    Shaded {
        rgb,
        edge_rays,
        secondary,
    }
}

/// What a pixel shows, as far as finding edges goes: a surface's colour (see `centre_row`)
/// packed below a flag, or no surface (`NO_SURFACE`), one word to compare with a neighbour's.
fn edge_key(surface: Option<[u8; 3]>) -> u32 {
    surface.map_or(NO_SURFACE, |[r, g, b]| {
        1 << 24 | u32::from(r) << 16 | u32::from(g) << 8 | u32::from(b)
    })
}

/// The `edge_key` of a pixel that sees no surface.
const NO_SURFACE: u32 = 0;

/// Whether two pixels' `edge_key`s differ visibly: one sees a surface and the other does not,
/// or their colours differ by more than one level in a channel (backgrounds never differ).
fn visibly_different(a: u32, b: u32) -> bool {
    let channel = |key: u32, shift: u32| (key >> shift) as u8;
    a != b
        && (a >> 24 != b >> 24
            || [16, 8, 0]
                .into_iter()
                .any(|shift| channel(a, shift).abs_diff(channel(b, shift)) > 1))
}

/// The columns of each row from its first hit to its last (empty for a row without one).
fn hit_spans(g: &GBuffer) -> Vec<std::ops::Range<usize>> {
    g.triangle
        .chunks(g.width as usize)
        .map(|line| match line.iter().position(|&t| t != NO_HIT) {
            None => 0..0,
            Some(first) => first..line.iter().rposition(|&t| t != NO_HIT).unwrap_or(first) + 1,
        })
        .collect()
}

/// The columns of `row` that hold a hit or touch one (given every row's `hit_spans`): the only
/// pixels that can be an edge.
fn near_hits(spans: &[std::ops::Range<usize>], row: usize, width: usize) -> std::ops::Range<usize> {
    let around = &spans[row.saturating_sub(1)..(row + 2).min(spans.len())];
    let (first, end) = around
        .iter()
        .filter(|span| !span.is_empty())
        .fold((usize::MAX, 0), |(first, end), span| {
            (first.min(span.start), end.max(span.end))
        });
    if first == usize::MAX {
        return 0..0;
    }
    first.saturating_sub(1)..(end + 1).min(width)
}

impl<S: Surfaces> Shading<'_, S> {
    /// Centre rays of columns `span` of a row: the shaded sRGB colour into `out` and, when
    /// anti-aliasing, into `edge_keys` the `edge_key` of the colour that decides where edges
    /// are (the untextured albedo lit without shadows or gloss for a textured surface; the
    /// shaded colour otherwise). Pixels of a plain background are left as they are.
    fn centre_row(
        &self,
        g: &GBuffer,
        row: usize,
        span: std::ops::Range<usize>,
        out: &mut [u8],
        mut edge_keys: Option<&mut [u32]>,
    ) {
        let width = g.width as usize;
        let k = self.camera.intrinsics;
        let row_y = k.ray_through_pixel(row as u32, 0).y;
        let mut last = LastMatte::default();
        let mut ahead = SurfacesAhead::default();
        let (mut shaded, mut untextured) = (LastEncoded::default(), LastEncoded::default());
        let end = span.end;
        for col in span {
            let i = row * width + col;
            let hit = (g.triangle[i] != NO_HIT).then(|| (g.depth[i], g.triangle[i]));
            if hit.is_none() && self.plain_background {
                continue;
            }
            let (u, v) = (col as f64 + 0.5, row as f64 + 0.5);
            let view = self.centre_view(row, col, row_y);
            let found = hit.and_then(|(_, tri)| {
                self.surfaces
                    .textured(tri)
                    .then(|| self.surface_ahead(g, row, col..end, &mut ahead))
            });
            let (linear, unshadowed) =
                self.radiance_with_irradiance(hit, view, (u, v), &mut last, found.as_ref());
            let colour = shaded.encode(linear);
            out[3 * col..3 * col + 3].copy_from_slice(&colour);
            if let Some(keys) = edge_keys.as_deref_mut() {
                let deciding = hit.map(|(_, tri)| {
                    if self.surfaces.textured(tri) {
                        let albedo = self.surfaces.flat(tri);
                        untextured.encode(reflected(
                            &self.lighting.film,
                            albedo,
                            unshadowed,
                            [0.0; 3],
                        ))
                    } else {
                        colour
                    }
                });
                keys[col] = edge_key(deciding);
            }
        }
    }

    /// The direction of the centre ray of pixel (`col`, `row`), camera axes; `row_y` is that
    /// of the row's rays when the camera is a pinhole.
    fn centre_view(&self, row: usize, col: usize, row_y: f64) -> DVec3 {
        match &self.pinhole_columns {
            Some(x) => DVec3::new(x[col], row_y, 1.0),
            None => self
                .camera
                .intrinsics
                .ray_through(col as f64 + 0.5, row as f64 + 0.5),
        }
    }

    /// The surface the centre ray of the first pixel of `cols` (of row `row`, on a textured
    /// triangle) meets: from `ahead` when it was found with the pixels before it, else found
    /// now together with those after it that also meet textured triangles, up to `LANES` (the
    /// material reads its fields for a span at once: `Surfaces::at_span`).
    fn surface_ahead(
        &self,
        g: &GBuffer,
        row: usize,
        cols: std::ops::Range<usize>,
        ahead: &mut SurfacesAhead,
    ) -> Ahead {
        let col = cols.start;
        if !ahead.cols.contains(&col) {
            let width = g.width as usize;
            let row_y = self.camera.intrinsics.ray_through_pixel(row as u32, 0).y;
            let mut hits = [(0, DVec3::ZERO, 0.0); LANES];
            let mut n = 0;
            for c in cols.take(LANES) {
                let tri = g.triangle[row * width + c];
                if tri == NO_HIT || !self.surfaces.textured(tri) {
                    break;
                }
                let depth = f64::from(g.depth[row * width + c]);
                let view = self.centre_view(row, c, row_y);
                let geometry = hit_geometry(self.camera, self.mesh, tri, view, depth);
                ahead.found[n].geometry = geometry;
                hits[n] = (tri, geometry.0, geometry.2);
                n += 1;
            }
            ahead.cols = col..col + n;
            let mut surfaces = [SurfacesAhead::NONE; LANES];
            self.surfaces.at_span(&hits[..n], &mut surfaces[..n]);
            for (a, s) in ahead.found.iter_mut().zip(surfaces) {
                a.surface = s;
            }
        }
        ahead.found[col - ahead.cols.start]
    }

    /// Re-shades from four fixed sub-pixel rays every pixel (near the hits of `spans`, see
    /// `hit_spans`) whose `edge_keys` entry (its deciding colour, or that it sees no surface)
    /// differs visibly from a neighbour's. The sub-rays' first hits are found for all those
    /// pixels at once (`TraceMesh::sample_hits`); returns how, None when no pixel needed it.
    fn antialias_edges(
        &self,
        g: &GBuffer,
        edge_keys: &[u32],
        spans: &[std::ops::Range<usize>],
        rgb: &mut [u8],
    ) -> Option<Visibility> {
        let width = g.width as usize;
        let differs = |i: usize, j: usize| visibly_different(edge_keys[i], edge_keys[j]);
        let edges: Vec<Vec<u32>> = (0..g.height as usize)
            .into_par_iter()
            .map(|row| {
                near_hits(spans, row, width)
                    .filter(|&col| {
                        let i = row * width + col;
                        (col > 0 && differs(i, i - 1))
                            || (col + 1 < width && differs(i, i + 1))
                            || (row > 0 && differs(i, i - width))
                            || (i + width < g.triangle.len() && differs(i, i + width))
                    })
                    .map(|col| col as u32)
                    .collect()
            })
            .collect();
        let edges = PixelSet::from_rows(&edges);
        if edges.is_empty() {
            return None;
        }
        let (hits, found) = self.mesh.sample_hits(self.camera, &edges, &EDGE_SAMPLES);
        rgb.par_chunks_mut(width * 3)
            .enumerate()
            .for_each(|(row, out)| {
                let mut last = LastMatte::default();
                for i in edges.in_rows(row..row + 1) {
                    let col = edges.at(i).1 as usize;
                    let mean = self.edge_pixel(col, row, &hits[i], &mut last);
                    out[3 * col..3 * col + 3].copy_from_slice(&encode(mean));
                }
            });
        Some(found)
    }

    /// The kinds of ray the lighting traces from a surface point (see `light`).
    fn secondary(&self) -> Vec<SecondaryRays> {
        let l = self.lighting;
        let shadows = l.sun.is_some() && l.shadows;
        let surrounding = l.environment.is_some() || l.sky.is_some() || l.ground.is_some();
        let occlusion = surrounding && !self.hemisphere.is_empty();
        [
            (shadows, SecondaryRays::Shadow),
            (occlusion, SecondaryRays::Occlusion),
        ]
        .into_iter()
        .filter_map(|(cast, kind)| cast.then_some(kind))
        .collect()
    }

    /// Mean linear radiance of the four sub-rays of pixel (`col`, `row`), which first meet
    /// the surfaces `hits`.
    ///
    /// Each sub-ray is lit at its own point, with its own normal. What it sees there is shared
    /// within the pixel: a sub-ray meeting an untextured triangle an earlier sub-ray met takes
    /// that radiance (a flat triangle's shade barely changes within a pixel), and one meeting
    /// a textured triangle takes the surface an earlier sub-ray found where the material
    /// `continues`. Materials filter their texture over the whole pixel's footprint, so one
    /// evaluation per pixel and face is the filter every other pixel gets; evaluating at each
    /// sub-ray would blur an edge pixel's texture more than its neighbours'.
    fn edge_pixel(
        &self,
        col: usize,
        row: usize,
        hits: &[Option<(f32, u32)>; EDGE_SAMPLES.len()],
        last: &mut LastMatte,
    ) -> [f64; 3] {
        let k = self.camera.intrinsics;
        let mut radiances = FoundInPixel::<[f64; 3]>::default();
        let mut surfaces = FoundInPixel::<Surface>::default();
        EDGE_SAMPLES
            .iter()
            .zip(hits)
            .fold([0.0; 3], |acc, (&(du, dv), &hit)| {
                let (u, v) = (col as f64 + du, row as f64 + dv);
                let view = k.ray_through(u, v);
                let c = match hit {
                    None => self.backdrop(view, u, v),
                    Some((depth, tri)) if self.surfaces.textured(tri) => {
                        let surface = surfaces.get_or_insert(
                            tri,
                            |earlier| self.surfaces.continues(earlier, tri),
                            || self.surface_at_centre(tri, depth, (col, row)),
                        );
                        self.hit_radiance(view, depth, tri, (u, v), Some(surface)).0
                    }
                    Some((depth, tri)) => radiances.get_or_insert(
                        tri,
                        |earlier| earlier == tri,
                        || self.matte_radiance(view, depth, tri, (u, v), last).0,
                    ),
                };
                std::array::from_fn(|k| acc[k] + c[k] / 4.0)
            })
    }

    /// Linear radiance along the ray `view` through image point (u, v), given what it hit,
    /// and the diffuse irradiance there as if no shadow fell (zero for the backdrop).
    fn radiance_with_irradiance(
        &self,
        hit: Option<(f32, u32)>,
        view: DVec3,
        (u, v): (f64, f64),
        last: &mut LastMatte,
        ahead: Option<&Ahead>,
    ) -> RadianceAndIrradiance {
        match (hit, ahead) {
            (None, _) => (self.backdrop(view, u, v), [0.0; 3]),
            (Some(_), Some(a)) => self.lit(view, &a.surface, a.geometry, (u, v)),
            (Some((depth, tri)), None) => self.matte_radiance(view, depth, tri, (u, v), last),
        }
    }

    /// `hit_radiance` of an untextured hit, taken from `last` when it saw the same side of
    /// the same matte triangle under uniform light (the same bits: nothing in the sum then
    /// depends on where the triangle is met), and kept there.
    fn matte_radiance(
        &self,
        view: DVec3,
        depth: f32,
        tri: u32,
        pixel: (f64, f64),
        last: &mut LastMatte,
    ) -> RadianceAndIrradiance {
        let side = self.uniform_side(tri, view);
        match (side, last.0) {
            (Some(side), Some((seen, light))) if side == seen => light,
            _ => {
                let light = self.hit_radiance(view, depth, tri, pixel, None);
                if let Some(side) = side {
                    last.0 = Some((side, light));
                }
                light
            }
        }
    }

    /// The triangle and the side of it seen along `view`, when it shows one radiance over
    /// that side: a matte, untextured surface under uniform light.
    fn uniform_side(&self, tri: u32, view: DVec3) -> Option<TriangleSide> {
        let uniform = self.uniform_light && self.surfaces.matte(tri);
        uniform.then(|| (tri, sees_back(self.camera, self.mesh, tri, view)))
    }

    /// The surface of triangle `tri`'s material where the centre ray of pixel `(col, row)`
    /// meets the triangle's plane (at `depth` along it if it runs along the plane), filtered
    /// over the pixel: what the pixel would show were the face all it saw.
    fn surface_at_centre(&self, tri: u32, depth: f32, (col, row): (usize, usize)) -> Surface {
        let centre = self
            .camera
            .intrinsics
            .ray_through(col as f64 + 0.5, row as f64 + 0.5);
        let (point, _, footprint) =
            hit_geometry(self.camera, self.mesh, tri, centre, f64::from(depth));
        self.surfaces.at(tri, point, footprint)
    }

    /// Linear radiance and unshadowed irradiance where the ray along `view` through image
    /// point `pixel` meets triangle `tri` at planar `depth`, with the surface there (`given`,
    /// else the material's at that point).
    fn hit_radiance(
        &self,
        view: DVec3,
        depth: f32,
        tri: u32,
        pixel: (f64, f64),
        given: Option<Surface>,
    ) -> RadianceAndIrradiance {
        let (point, normal, footprint) =
            hit_geometry(self.camera, self.mesh, tri, view, f64::from(depth));
        let surface = given.unwrap_or_else(|| self.surfaces.at(tri, point, footprint));
        self.lit(view, &surface, (point, normal, footprint), pixel)
    }

    /// `hit_radiance` of a hit whose geometry (`hit_geometry`) and surface are known.
    fn lit(
        &self,
        view: DVec3,
        surface: &Surface,
        geometry: (DVec3, DVec3, f64),
        pixel: (f64, f64),
    ) -> RadianceAndIrradiance {
        let light = self.light(view, surface, geometry, pixel);
        let film = &self.lighting.film;
        let radiance = reflected(film, surface.albedo, light.diffuse, light.specular);
        (radiance, light.unshadowed)
    }

    /// The light a surface at `point` with facing `n` (seen with pixels `footprint` metres
    /// wide) receives along `view`, seen through image point `pixel`: diffuse irradiance with
    /// and without the sun's shadow and the sky's occlusion, and the glossy reflection.
    fn light(
        &self,
        view: DVec3,
        surface: &Surface,
        (point, n, footprint): (DVec3, DVec3, f64),
        pixel: (f64, f64),
    ) -> Light {
        let l = self.lighting;
        let gloss = Lobe::of(surface);
        let to_eye = gloss
            .as_ref()
            .map(|_| -(self.camera.rotation * view).normalize());
        let mut light = Light {
            diffuse: [l.ambient; 3],
            unshadowed: [l.ambient; 3],
            specular: [0.0; 3],
        };
        // Each light in a fixed order, so both sums round alike where no shadow falls.
        // `reaches`: the share of the light not shadowed.
        let mut add = |direction: DVec3, colour: [f64; 3], reaches: f64| {
            let cos = n.dot(direction);
            if cos <= 0.0 {
                return;
            }
            for (sum, c) in light.unshadowed.iter_mut().zip(colour) {
                *sum += c * cos;
            }
            if reaches == 0.0 {
                return;
            }
            // A whole light multiplies by nothing: the same bits as before soft shadows.
            let cos = if reaches == 1.0 { cos } else { cos * reaches };
            for (sum, c) in light.diffuse.iter_mut().zip(colour) {
                *sum += c * cos;
            }
            if let (Some(lobe), Some(to_eye)) = (&gloss, to_eye) {
                let glint = lobe.glint(n, direction, to_eye) * cos;
                for (sum, c) in light.specular.iter_mut().zip(colour) {
                    *sum += c * glint;
                }
            }
        };
        if let Some(lights) = &self.studio {
            for (direction, intensity) in lights {
                add(*direction, [*intensity; 3], 1.0);
            }
        }
        let open = self.openness(point, n, pixel, footprint);
        if let Some(sun) = &l.sun {
            add(sun.direction, sun.colour, open.sun);
        }
        let surrounding = if let Some(environment) = &l.environment {
            // The map's light replaces the sky's: SH irradiance, scaled by the open share.
            Some(environment_light(environment, n, open))
        } else if l.sky.is_some() || l.ground.is_some() {
            // Irradiance of a sky dome and a ground below, for a surface tilted by n.z.
            Some(sky_light(l, point, n, open))
        } else {
            None
        };
        if let Some((seen, open)) = surrounding {
            for k in 0..3 {
                light.diffuse[k] += seen[k];
                light.unshadowed[k] += open[k];
            }
        }
        light
    }

    /// What `point` (facing `n`, pixels `footprint` wide) sees of the lights: looked up in the
    /// sample's lighting cache, or traced from this pixel (`shading: "per_pixel"`).
    fn openness(&self, point: DVec3, n: DVec3, pixel: (f64, f64), footprint: f64) -> Openness {
        let rays = LightRays {
            mesh: self.mesh,
            lighting: self.lighting,
            sun_disk: &self.sun_disk,
            hemisphere: &self.hemisphere,
        };
        match self.cache {
            Some(cache) => cache.openness(self.mesh, self.lighting, point, n, footprint),
            None => rays.openness(point, n, || pixel_turn(pixel.0, pixel.1)),
        }
    }

    fn backdrop(&self, view: DVec3, u: f64, v: f64) -> [f64; 3] {
        match self.backdrop {
            Backdrop::Colour(_) => self.background,
            Backdrop::Sky {
                zenith,
                horizon,
                ground,
            } => {
                let up = (self.camera.rotation * view).normalize().z;
                let film = &self.lighting.film;
                if up < 0.0 {
                    ground.map(|c| film.display(c))
                } else {
                    let t = up.sqrt();
                    std::array::from_fn(|k| film.display(horizon[k] + (zenith[k] - horizon[k]) * t))
                }
            }
            Backdrop::Environment {
                map,
                intensity,
                rotation,
            } => {
                let world = turn_about_z(self.camera.rotation * view, -rotation);
                let film = &self.lighting.film;
                map.radiance(world).map(|c| film.display(c * intensity))
            }
            Backdrop::Image {
                image,
                origin,
                size,
            } => {
                let k = self.camera.intrinsics;
                let (w, h) = (f64::from(k.width), f64::from(k.height));
                image.sample(
                    origin.0 + u / w * size.0,
                    origin.1 + v / h * size.1,
                    size.0 / w,
                )
            }
        }
    }
}

/// World normal of the triangle, turned towards the camera (surfaces are two-sided).
pub(super) fn facing_normal(camera: &Camera, mesh: &TraceMesh, tri: u32, view: DVec3) -> DVec3 {
    let n = mesh.normal(tri);
    if sees_back(camera, mesh, tri, view) {
        -n
    } else {
        n
    }
}

/// Whether the ray along `view` (camera axes) meets triangle `tri` from behind its winding.
fn sees_back(camera: &Camera, mesh: &TraceMesh, tri: u32, view: DVec3) -> bool {
    mesh.normal(tri).dot(camera.rotation * view) > 0.0
}

/// Where the ray along `view` (camera axes, unit z) meets triangle `tri` at planar `depth`:
/// the world point, the normal facing the camera, and the pixel's footprint there in metres.
pub(super) fn hit_geometry(
    camera: &Camera,
    mesh: &TraceMesh,
    tri: u32,
    view: DVec3,
    depth: f64,
) -> (DVec3, DVec3, f64) {
    let k = camera.intrinsics;
    // The plane gives the point to f64 precision, where the f32 depth label may not (a camera
    // far away); the label is the fallback for a ray along the plane.
    let dir = camera.rotation * view;
    let on_plane = mesh.plane_hit(tri, camera.position, dir);
    let depth = if on_plane.is_finite() && on_plane > 0.0 {
        on_plane
    } else {
        depth
    };
    let point = camera.position + dir * depth;
    let normal = facing_normal(camera, mesh, tri, view);
    // A pixel stretches over a surface seen at a slant (up to ten times, at grazing rays).
    let slant = normal.dot(-(camera.rotation * view).normalize()).max(0.1);
    (point, normal, depth / k.fx.min(k.fy) / slant)
}

/// Linear colour → sRGB 8-bit.
fn encode(linear: [f64; 3]) -> [u8; 3] {
    let lut = srgb_lut();
    let byte = |c: f64| lut[round_half_up(c.clamp(0.0, 1.0) * (LUT_SIZE - 1) as f64)];
    // Spelled out: `array::map` is not always inlined here, and this runs for every pixel.
    [byte(linear[0]), byte(linear[1]), byte(linear[2])]
}

/// `y.round()` for y ≥ 0 (NaN gives 0, as `round` does): ⌊2y⌋ is exact (doubling is), and
/// ⌈⌊2y⌋ / 2⌉ in integers is y rounded half up. Truncation is one instruction on any x86-64,
/// where `round` is a library call.
fn round_half_up(y: f64) -> usize {
    ((2.0 * y) as usize).div_ceil(2)
}

const LUT_SIZE: usize = 4096;

/// Linear → sRGB 8-bit encoding table.
fn srgb_lut() -> &'static [u8; LUT_SIZE] {
    static LUT: OnceLock<[u8; LUT_SIZE]> = OnceLock::new();
    LUT.get_or_init(|| {
        std::array::from_fn(|i| {
            let l = i as f64 / (LUT_SIZE - 1) as f64;
            let s = if l <= 0.003_130_8 {
                12.92 * l
            } else {
                1.055 * libm::pow(l, 1.0 / 2.4) - 0.055
            };
            (s * 255.0).round() as u8
        })
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rounding_half_up_is_rounding() {
        let mut cases = vec![
            0.0,
            0.5,
            1.0,
            1.5,
            4094.5,
            4095.0,
            f64::NAN,
            f64::MIN_POSITIVE,
        ];
        // Halves, their neighbours one ulp either side, and a sweep of the table's range.
        for k in 0..4095 {
            let half = f64::from(k) + 0.5;
            cases.extend([half, half.next_down(), half.next_up()]);
        }
        cases.extend((0..100_000).map(|i| f64::from(i) * 0.040_95));
        for y in cases {
            assert_eq!(round_half_up(y), y.round() as usize, "{y}");
        }
    }

    #[test]
    fn edges_are_where_a_surface_meets_none_or_its_colour_steps_by_two_levels() {
        let grey = Some([100, 100, 100]);
        let edge = |a, b| visibly_different(edge_key(a), edge_key(b));
        // Seeing a surface or not differs whatever the colours, even black against none.
        assert!(edge(grey, None) && edge(None, grey) && edge(Some([0; 3]), None));
        assert!(!edge(None, None));
        for channel in 0..3 {
            for (step, differs) in [(0, false), (1, false), (2, true), (255 - 100, true)] {
                let mut up = [100u8; 3];
                up[channel] += step;
                let mut down = [100u8; 3];
                down[channel] = down[channel].saturating_sub(step);
                assert_eq!(edge(grey, Some(up)), differs, "{up:?}");
                assert_eq!(edge(Some(down), grey), differs, "{down:?}");
            }
        }
    }

    #[test]
    fn edges_are_looked_for_wherever_a_hit_is_or_touches() {
        let (width, height) = (23usize, 17usize);
        // Scattered hits (a fixed arithmetic pattern), a row without any, hits on the borders.
        let hits = |row: usize, col: usize| {
            row != 8 && ((row * 7 + col * 13).is_multiple_of(29) || (row == 0 && col == 22))
        };
        let triangle = (0..height)
            .flat_map(|row| (0..width).map(move |col| if hits(row, col) { 1 } else { NO_HIT }))
            .collect();
        let g = GBuffer {
            width: width as u32,
            height: height as u32,
            depth: vec![1.0; width * height],
            triangle,
            visibility: crate::render::Visibility::Rasterised,
        };
        let spans = hit_spans(&g);
        for row in 0..height {
            let searched = near_hits(&spans, row, width);
            for col in 0..width {
                let touched = [(0, 0), (0, -1), (0, 1), (-1, 0), (1, 0)]
                    .iter()
                    .any(|(dr, dc)| {
                        let (r, c) = (row as isize + dr, col as isize + dc);
                        (0..height as isize).contains(&r)
                            && (0..width as isize).contains(&c)
                            && hits(r as usize, c as usize)
                    });
                assert!(!touched || searched.contains(&col), "({row}, {col})");
            }
        }
        // Nothing to look for far from every hit.
        let empty = GBuffer {
            triangle: vec![NO_HIT; width * height],
            ..g
        };
        assert!((0..height).all(|row| near_hits(&hit_spans(&empty), row, width).is_empty()));
    }
}
