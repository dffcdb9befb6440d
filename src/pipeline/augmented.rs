//! Augmented copies of a view: the operations drawn for a copy, the camera a geometric one
//! makes, and the copy's layers. In exact mode the view is rendered again through the new
//! camera, so every label is exact; in image mode the rendered layers are warped (RGB
//! bilinearly, labels by nearest neighbour, pixels without a source invalid; normals in camera
//! axes turn with the camera). Photometric operations then act on the RGB images only (the
//! loaded and the unloaded one alike, with the same drawn values), in the order the recipe
//! lists them; pixels without a source stay black. Both modes write one camera: the one under
//! which the moved picture is exact, lens included. Flow is not defined on a warped image:
//! the recipe refuses that combination.

use super::view::{RenderedLayers, ViewCamera};
use crate::augment::{
    self, Blur, ColourJitter, Erasing, Exposure, Frame, Gamma, Jpeg, Noise, Pinhole, Similarity,
    Vignette,
};
use crate::cameras::Camera;
use crate::output::{DamageLayers, Flow, FrameFlow, ViewLayers};
use crate::render::ViewVisibility;
use crate::scene::{AugmentSpec, DatasetSpec, GeometryMode, NormalsFrame, Operation};
use crate::seeds::{Scope, Stream};
use anyhow::{Result, anyhow};
use glam::{DMat3, DVec3};
use serde::Serialize;
use std::sync::OnceLock;

/// An operation as applied to one copy: the values drawn for it.
#[derive(Clone, Debug, PartialEq, Serialize, schemars::JsonSchema)]
#[serde(tag = "op", rename_all = "snake_case")]
pub enum Applied {
    /// Zoom, rotation and shift: the similarity of pixel coordinates.
    Warp(Similarity),
    /// A window resized to the frame: the similarity of pixel coordinates.
    Crop(Similarity),
    /// Colour jitter.
    ColourJitter(ColourJitter),
    /// Exposure.
    Exposure(Exposure),
    /// Gamma.
    Gamma(Gamma),
    /// Vignetting.
    Vignette(Vignette),
    /// Sensor noise.
    Noise(Noise),
    /// Blur.
    Blur(Blur),
    /// JPEG re-compression.
    Jpeg(Jpeg),
    /// Cut-out: the rectangles erased.
    Erase(Erasing),
}

impl Applied {
    /// The similarity of a geometric operation.
    pub fn geometry(&self) -> Option<Similarity> {
        match self {
            Applied::Warp(s) | Applied::Crop(s) => Some(*s),
            _ => None,
        }
    }
}

/// Which copy of which image: sample, camera view, the pose it belongs to (both eyes of a
/// stereo pair share one pose; otherwise the pose is the view) and the copy.
#[derive(Clone, Copy, Debug)]
struct CopyOf {
    /// Sample index.
    pub sample: u64,
    /// Camera view within the sample.
    pub view: u32,
    /// The pose of the view: view / 2 in a stereo rig, else the view.
    pub pose: u32,
    /// Copy index.
    pub copy: u32,
}

/// The operations of one copy, each drawn from its own stream keyed by the copy and by the
/// operation's kind and how many of that kind come before it in the list ("augment 0 blur
/// 1": the copy's second blur). So adding, removing or moving operations of other kinds never
/// changes an operation's draws. A geometric operation draws per pose, so that both eyes of
/// a stereo pair move alike and stay a rigid pair; the others per view. Operations the
/// probabilities skip are left out.
fn draw_copy(spec: &AugmentSpec, seed: u64, of: CopyOf, size: (u32, u32)) -> Vec<Applied> {
    draw_operations(
        &spec.operations,
        &format!("augment {}", of.copy),
        seed,
        of,
        size,
    )
}

/// The sensor's operations for view `view` of sample `sample`, each drawn from its own stream
/// ("sensor vignette 0", ...) keyed by the view, as a copy's are.
pub fn draw_sensor(dataset: &DatasetSpec, sample: u64, view: u32) -> Vec<Applied> {
    let of = CopyOf {
        sample,
        view,
        pose: view,
        copy: 0,
    };
    let size = (dataset.camera.width, dataset.camera.height);
    draw_operations(&dataset.sensor, "sensor", dataset.seed, of, size)
}

/// `operations` drawn for `of`, each from the stream "{prefix} {kind} {occurrence}".
fn draw_operations(
    operations: &[Operation],
    prefix: &str,
    seed: u64,
    of: CopyOf,
    (width, height): (u32, u32),
) -> Vec<Applied> {
    let (w, h) = (width as usize, height as usize);
    let mut seen: Vec<&str> = Vec::new();
    operations
        .iter()
        .filter_map(|op| {
            let kind = op.name();
            let occurrence = seen.iter().filter(|k| **k == kind).count();
            seen.push(kind);
            let name = format!("{prefix} {kind} {occurrence}");
            let at = if op.is_geometric() { of.pose } else { of.view };
            let stream = &mut Stream::new(seed, Scope::View(of.sample, at), &name);
            match op {
                Operation::Warp(s) => s.draw(stream, w, h).map(Applied::Warp),
                Operation::Crop(s) => s.draw(stream, w, h).map(Applied::Crop),
                Operation::ColourJitter(s) => s.draw(stream).map(Applied::ColourJitter),
                Operation::Exposure(s) => s.draw(stream).map(Applied::Exposure),
                Operation::Gamma(s) => s.draw(stream).map(Applied::Gamma),
                Operation::Vignette(s) => s.draw(stream).map(Applied::Vignette),
                Operation::Noise(s) => s.draw(stream).map(Applied::Noise),
                Operation::Blur(s) => s.draw(stream).map(Applied::Blur),
                Operation::Jpeg(s) => s.draw(stream).map(Applied::Jpeg),
                Operation::Erase(s) => s.draw(stream, w, h).map(Applied::Erase),
            }
        })
        .collect()
}

/// The operations drawn for copy `copy` of camera view `view` (whose camera is `drawn`) of
/// sample `sample`, and the camera its files agree with. Fails when the copy's camera cannot
/// be made (a rotation of non-square pixels) or, rendered again in exact mode, would have
/// pixels without a ray.
pub fn copy_camera(
    dataset: &DatasetSpec,
    (sample, view, copy): (u64, u32, u32),
    drawn: &ViewCamera,
) -> Result<(Vec<Applied>, Camera)> {
    let of = CopyOf {
        sample,
        view,
        pose: drawn.stereo.map_or(view, |(pose, _)| pose),
        copy,
    };
    let size = (dataset.camera.width, dataset.camera.height);
    let operations = draw_copy(&dataset.augment, dataset.seed, of, size);
    let camera = match operations.iter().find_map(Applied::geometry) {
        Some(sim) => moved_camera(&drawn.camera, &sim)?,
        None => return Ok((operations, drawn.camera)),
    };
    if dataset.augment.mode == GeometryMode::Exact {
        camera.intrinsics.check_lens().map_err(|e| {
            anyhow!("sample {sample}, view {view}, copy {copy}: dataset.augment moves the camera, and {e}")
        })?;
    }
    Ok((operations, camera))
}

/// The camera that sees the picture `camera` sees, moved by the pixel similarity `sim`:
/// K′ with f′ = s·f and p′ = s·R(θ)(p − c) + c + t, the camera turned about its optical axis
/// by θ (c2w′ = c2w·R_z(θ)ᵀ), and the lens seen from the turned axes (its tangential
/// coefficients turn with the picture; see [`Distortion::turned`]). The distortion centre is
/// the principal point, which the similarity moves with the picture, so every pixel of the
/// moved picture is exactly the projection through the new camera, for any lens.
///
/// [`Distortion::turned`]: crate::cameras::Distortion::turned
pub fn moved_camera(camera: &Camera, sim: &Similarity) -> Result<Camera> {
    let k = camera.intrinsics;
    let moved = sim
        .intrinsics(&Pinhole {
            fx: k.fx,
            fy: k.fy,
            cx: k.cx,
            cy: k.cy,
        })
        .map_err(|e| anyhow!("an augmentation's warp: {e}"))?;
    let mut intrinsics = k;
    (intrinsics.fx, intrinsics.fy, intrinsics.cx, intrinsics.cy) =
        (moved.fx, moved.fy, moved.cx, moved.cy);
    intrinsics.distortion = k.distortion.turned(sim.angle);
    Ok(Camera {
        intrinsics,
        ..turned_camera(camera, sim)
    })
}

/// `camera` turned about its optical axis as the similarity `sim` turns the picture:
/// c2w′ = c2w·R_z(θ)ᵀ (the intrinsics left as they are).
pub fn turned_camera(camera: &Camera, sim: &Similarity) -> Camera {
    Camera {
        rotation: camera.rotation * optical_axis_turn(sim).transpose(),
        ..*camera
    }
}

/// R_z(θ) of the similarity: the turn about the optical axis taking camera-axis vectors of
/// the original camera to those of the moved one (c2w′ = c2w·R_zᵀ, so x′ = R_z·x).
fn optical_axis_turn(sim: &Similarity) -> DMat3 {
    let r = sim.camera_rotation();
    DMat3::from_cols(
        DVec3::new(r[0][0], r[1][0], r[2][0]),
        DVec3::new(r[0][1], r[1][1], r[2][1]),
        DVec3::new(r[0][2], r[1][2], r[2][2]),
    )
}

/// A copy of a view: its base (the view itself, or the view rendered again through the
/// copy's camera), the image-space warp when the geometry is warped, and the photometric
/// operations.
pub struct AugmentedView<'a> {
    base: &'a dyn RenderedLayers,
    warp: Option<Similarity>,
    operations: &'a [Applied],
    /// The turn applied to normals: the warp's, when normals are in camera axes.
    normals_turn: Option<DMat3>,
    rgb: OnceLock<Vec<u8>>,
    depth: OnceLock<Vec<f32>>,
    cracks: OnceLock<Vec<u8>>,
    rest_rgb: OnceLock<Vec<u8>>,
    rest_depth: OnceLock<Vec<f32>>,
}

impl<'a> AugmentedView<'a> {
    /// The copy of `base` made by `operations`; `warp` moves pixels (image mode only);
    /// normals are written in `normals` axes.
    pub fn new(
        base: &'a dyn RenderedLayers,
        warp: Option<Similarity>,
        operations: &'a [Applied],
        normals: NormalsFrame,
    ) -> Self {
        let normals_turn = warp
            .as_ref()
            .filter(|_| normals == NormalsFrame::Camera)
            .map(optical_axis_turn);
        AugmentedView {
            base,
            warp,
            operations,
            normals_turn,
            rgb: OnceLock::new(),
            depth: OnceLock::new(),
            cracks: OnceLock::new(),
            rest_rgb: OnceLock::new(),
            rest_depth: OnceLock::new(),
        }
    }

    /// An RGB image of the base moved by the warp (bilinearly), then through the photometric
    /// operations.
    fn augmented_rgb(&self, rgb: &[u8]) -> Vec<u8> {
        let mut rgb = match &self.warp {
            Some(sim) => augment::warp_rgb(rgb, self.frame(), sim),
            None => rgb.to_vec(),
        };
        let valid = self
            .warp
            .map(|sim| augment::warp_validity(self.frame(), &sim));
        // The operations are validated; an encoder failing in memory is a bug.
        self.photometric(&mut rgb, valid.as_deref())
            .expect("photometric augmentations of a valid image");
        rgb
    }

    fn frame(&self) -> Frame {
        let (w, h) = self.base.size();
        Frame::same(w as usize, h as usize)
    }

    /// A label layer moved by the warp, if any.
    fn moved<T: Copy + Default + Send + Sync>(&self, layer: Vec<T>) -> Vec<T> {
        match &self.warp {
            Some(sim) => augment::warp_labels(&layer, self.frame(), sim),
            None => layer,
        }
    }

    /// The photometric operations, in order, on the (warped) RGB image. `valid` marks the
    /// pixels a warp gave a source: statistics (contrast's mean, a mean fill) leave the
    /// others out, and they are black again at the end, whatever noise, blur or JPEG put
    /// there.
    fn photometric(&self, rgb: &mut [u8], valid: Option<&[u8]>) -> Result<(), String> {
        let (w, h) = self.base.size();
        photometric(rgb, (w as usize, h as usize), self.operations, valid)
    }
}

/// The photometric `operations`, in order, on an RGB image of `(w, h)` pixels (geometric ones
/// are skipped: they act before). `valid` marks the pixels a warp gave a source: statistics
/// leave the others out, and they are black again at the end.
pub fn photometric(
    rgb: &mut [u8],
    (w, h): (usize, usize),
    operations: &[Applied],
    valid: Option<&[u8]>,
) -> Result<(), String> {
    for op in operations {
        match op {
            Applied::Warp(_) | Applied::Crop(_) => {}
            Applied::ColourJitter(p) => augment::colour_jitter(rgb, w, h, p, valid),
            Applied::Exposure(p) => augment::exposure(rgb, w, h, p),
            Applied::Gamma(p) => augment::gamma(rgb, w, h, p),
            Applied::Vignette(p) => augment::vignette(rgb, w, h, p),
            Applied::Noise(p) => augment::add_noise(rgb, w, h, p),
            Applied::Blur(p) => augment::blur(rgb, w, h, p),
            Applied::Jpeg(p) => augment::jpeg(rgb, w, h, p)?,
            Applied::Erase(p) => {
                augment::erase(rgb, w, h, p, valid);
            }
        }
    }
    for (pixel, _) in
        (rgb.chunks_exact_mut(3).zip(valid.into_iter().flatten())).filter(|(_, v)| **v == 0)
    {
        pixel.fill(0);
    }
    Ok(())
}

/// Pixels of an image of `(width, height)`.
fn pixels((w, h): (u32, u32)) -> usize {
    w as usize * h as usize
}

impl ViewLayers for AugmentedView<'_> {
    fn size(&self) -> (u32, u32) {
        self.base.size()
    }

    fn rgb(&self) -> &[u8] {
        self.rgb.get_or_init(|| self.augmented_rgb(self.base.rgb()))
    }

    fn depth(&self) -> &[f32] {
        self.depth
            .get_or_init(|| self.moved(self.base.depth().to_vec()))
    }

    fn mask(&self) -> Vec<u8> {
        self.moved(self.base.mask())
    }

    fn part_ids(&self) -> Vec<u32> {
        self.moved(self.base.part_ids())
    }

    fn instance_ids(&self) -> Vec<u32> {
        self.moved(self.base.instance_ids())
    }

    fn cracks(&self) -> &[u8] {
        self.cracks
            .get_or_init(|| self.moved(self.base.cracks().to_vec()))
    }

    fn erased(&self) -> Vec<u8> {
        let (w, h) = self.base.size();
        let mut mask = vec![0u8; (w * h) as usize];
        for op in self.operations {
            if let Applied::Erase(e) = op {
                for (m, e) in mask.iter_mut().zip(e.mask(w as usize, h as usize)) {
                    *m |= e;
                }
            }
        }
        mask
    }

    fn valid(&self) -> Vec<u8> {
        match &self.warp {
            Some(sim) => augment::warp_validity(self.frame(), sim),
            None => self.base.valid(),
        }
    }

    fn normals(&self) -> Vec<[f32; 3]> {
        let moved = self.moved(self.base.normals());
        match self.normals_turn {
            Some(turn) => moved
                .into_iter()
                .map(|n| (turn * DVec3::from(n.map(f64::from))).as_vec3().to_array())
                .collect(),
            None => moved,
        }
    }

    fn ray_distance(&self) -> Vec<f32> {
        // The warped camera keeps its centre, so each surface point keeps its distance.
        self.moved(self.base.ray_distance())
    }

    fn displacement(&self) -> Vec<[f32; 3]> {
        self.moved(self.base.displacement())
    }

    fn flow(&self) -> Flow {
        if self.warp.is_none() {
            return self.base.flow();
        }
        // The recipe refuses flow with image-space warps; should one get here, no pixel
        // claims a flow rather than one measured in another frame.
        Flow::invalid(pixels(self.size()))
    }

    fn frame_flow(&self) -> FrameFlow {
        if self.warp.is_none() {
            return self.base.frame_flow();
        }
        // Refused with image-space warps too, as `flow`.
        FrameFlow {
            next: Flow::invalid(pixels(self.size())),
            prev: Flow::invalid(pixels(self.size())),
        }
    }

    fn point_tracks(&self) -> Vec<[f64; 3]> {
        if self.warp.is_none() {
            return self.base.point_tracks();
        }
        // Refused with image-space warps too, as `flow`: no track rather than one measured
        // in another frame.
        Vec::new()
    }

    fn rest_rgb(&self) -> &[u8] {
        self.rest_rgb
            .get_or_init(|| self.augmented_rgb(self.base.rest_rgb()))
    }

    fn rest_depth(&self) -> &[f32] {
        self.rest_depth
            .get_or_init(|| self.moved(self.base.rest_depth().to_vec()))
    }

    fn damage(&self) -> DamageLayers {
        let base = self.base.damage();
        DamageLayers {
            class: self.moved(base.class),
            instance: self.moved(base.instance),
            crack_width_mm: self.moved(base.crack_width_mm),
            crack_coverage: self.moved(base.crack_coverage),
        }
    }
}

/// A copy's layers come from its base's (warped or not), found as the base's were.
impl RenderedLayers for AugmentedView<'_> {
    fn visibility(&self) -> ViewVisibility {
        self.base.visibility()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::augment::{BlurSpec, ExposureSpec, GammaSpec, NoiseSpec, Range, SigmaUnit};
    use crate::scene::WarpSpec;

    fn with(operations: &[Operation]) -> AugmentSpec {
        AugmentSpec {
            copies: 1,
            operations: operations.to_vec(),
            ..AugmentSpec::default()
        }
    }

    /// What copy `copy` of view `view` (pose `pose`) draws under `spec`, by kind.
    fn drawn(spec: &AugmentSpec, view: u32, pose: u32, copy: u32) -> Vec<(&'static str, Applied)> {
        let of = CopyOf {
            sample: 5,
            view,
            pose,
            copy,
        };
        let kind = |a: &Applied| match a {
            Applied::Warp(_) => "warp",
            Applied::Gamma(_) => "gamma",
            Applied::Noise(_) => "noise",
            Applied::Exposure(_) => "exposure",
            Applied::Blur(_) => "blur",
            _ => "other",
        };
        draw_copy(spec, 11, of, (64, 48))
            .into_iter()
            .map(|a| (kind(&a), a))
            .collect()
    }

    #[test]
    fn an_operation_draws_the_same_whatever_other_kinds_are_listed_around_it() {
        let gamma = Operation::Gamma(GammaSpec {
            gamma: Range::Span([0.5, 2.0]),
            probability: 0.5,
        });
        let noise = Operation::Noise(NoiseSpec::Gaussian {
            sigma: Range::Span([1.0, 9.0]),
            unit: SigmaUnit::Levels,
            probability: 0.5,
        });
        let exposure = Operation::Exposure(ExposureSpec {
            stops: Range::Span([-1.0, 1.0]),
            probability: 0.5,
        });
        let blur = Operation::Blur(BlurSpec::Defocus {
            radius: Range::Span([1.0, 2.0]),
            probability: 1.0,
        });
        let alone = with(&[gamma.clone(), noise.clone()]);
        // Others added before, between and after, and the two swapped.
        let crowded = with(&[exposure, noise, blur, gamma]);
        let only = |list: Vec<(&'static str, Applied)>| -> Vec<(&'static str, Applied)> {
            list.into_iter()
                .filter(|(k, _)| ["gamma", "noise"].contains(k))
                .collect()
        };
        let (mut seen, mut differ) = (0, 0);
        for copy in 0..200 {
            let mut a = only(drawn(&alone, 0, 0, copy));
            let mut b = only(drawn(&crowded, 0, 0, copy));
            a.sort_by_key(|(k, _)| *k);
            b.sort_by_key(|(k, _)| *k);
            assert_eq!(a, b, "copy {copy}");
            seen += a.len();
            differ += usize::from(drawn(&alone, 0, 0, copy) != drawn(&alone, 0, 0, copy + 1));
        }
        // Both operations were drawn often, and copies differ from one another.
        assert!(seen > 150 && differ > 150, "{seen} {differ}");
    }

    #[test]
    fn both_eyes_of_a_pair_draw_one_geometry_and_their_own_photometry() {
        let spec = with(&[
            Operation::Warp(WarpSpec::paper()),
            Operation::Noise(NoiseSpec::Gaussian {
                sigma: Range::Span([1.0, 9.0]),
                unit: SigmaUnit::Levels,
                probability: 1.0,
            }),
        ]);
        for pose in 0..20 {
            let (left, right) = (
                drawn(&spec, 2 * pose, pose, 0),
                drawn(&spec, 2 * pose + 1, pose, 0),
            );
            assert_eq!(left[0], right[0], "the warp of pose {pose}");
            assert_ne!(left[1], right[1], "each eye's own noise");
        }
        // Unpaired views keep their own geometry.
        assert_ne!(drawn(&spec, 0, 0, 0)[0], drawn(&spec, 1, 1, 0)[0]);
    }
}
