//! `--format nerfstudio`: one scene per sample (all views of one deformed structure are one
//! static scene), as nerfstudio's `nerfstudio-data` parser reads it:
//!
//! ```text
//! DIR/{sample:06}/transforms.json
//! DIR/{sample:06}/images/{stem}.png   the RGB (hard link)
//! DIR/{sample:06}/depth/{stem}.png    planar depth, 16-bit millimetres
//! DIR/{sample:06}/masks/{stem}.png    the structure mask (hard link); 0 = ignored by nerfstudio
//! DIR/{sample:06}/points.ply          points on the deformed surface (hard link), when the
//!                                     dataset wrote `points`; named by `ply_file_path`
//! ```
//!
//! Intrinsics are per frame (`fl_x fl_y cx cy w h`, in our pixel-centre-at-0.5 convention,
//! which is nerfstudio's), `camera_model` is `OPENCV` with each frame's `k1 k2 k3 p1 p2` when
//! any view is distorted and `PINHOLE` otherwise; `transform_matrix` is the view's
//! `c2w_opengl`. Depth is written in millimetres because nerfstudio reads depth images with
//! OpenCV (`IMREAD_ANYDEPTH`, no EXR unless enabled) and multiplies by its
//! `depth_unit_scale_factor`, whose default is 0.001.

use super::{Job, depth_mm, frames, intrinsics, needed, png16};
use anyhow::Result;
use serde_json::{Map, Value, json};

pub(super) fn write(job: &mut Job) -> Result<Value> {
    let (dataset, out, options) = (job.dataset, job.out, job.options);
    for (sample, views) in frames(dataset, options)? {
        let scene = out.join(format!("{:06}", sample.index));
        let cameras = views
            .iter()
            .map(|v| dataset.camera(v))
            .collect::<Result<Vec<_>>>()?;
        let distorted = cameras.iter().any(|c| c.distortion.is_some());
        // nerfstudio wants a mask (and a depth) for every frame or for none.
        let masks = views.iter().all(|v| v.file("mask.png").is_some());
        let depths = views.iter().all(|v| v.file("depth.exr").is_some());
        let depth_pngs = if depths {
            depth_mm::pngs_of(dataset, &views)?
                .into_iter()
                .map(Some)
                .collect()
        } else {
            vec![None; views.len()]
        };
        let mut list = Vec::with_capacity(views.len());
        for ((view, camera), depth_png) in views.iter().zip(&cameras).zip(depth_pngs) {
            let rgb = needed(view, "rgb.png", "nerfstudio")?;
            let image = format!("images/{}.png", view.stem);
            job.placer.place(dataset, rgb, &scene.join(&image))?;
            let [fx, fy, cx, cy] = intrinsics(&camera.k, view)?;
            let mut frame = Map::new();
            frame.insert("file_path".into(), json!(image));
            frame.insert("fl_x".into(), json!(fx));
            frame.insert("fl_y".into(), json!(fy));
            frame.insert("cx".into(), json!(cx));
            frame.insert("cy".into(), json!(cy));
            frame.insert("w".into(), json!(camera.width));
            frame.insert("h".into(), json!(camera.height));
            if distorted {
                let d = camera.distortion.unwrap_or_default();
                for (name, value) in [
                    ("k1", d.k1),
                    ("k2", d.k2),
                    ("k3", d.k3),
                    ("p1", d.p1),
                    ("p2", d.p2),
                ] {
                    frame.insert(name.into(), json!(value));
                }
            }
            frame.insert("transform_matrix".into(), json!(camera.c2w_opengl));
            if let Some((png, clamped)) = depth_png {
                let depth = format!("depth/{}.png", view.stem);
                job.placer.write(&scene.join(&depth), &png)?;
                job.summary.saturated += clamped.saturated;
                job.summary.raised += clamped.raised;
                frame.insert("depth_file_path".into(), json!(depth));
            }
            if masks {
                let mask = format!("masks/{}.png", view.stem);
                let from = view.file("mask.png").unwrap_or_default();
                job.placer.place(dataset, from, &scene.join(&mask))?;
                frame.insert("mask_path".into(), json!(mask));
            }
            list.push(Value::Object(frame));
            job.summary.views += 1;
        }
        let mut transforms = json!({
            "camera_model": if distorted { "OPENCV" } else { "PINHOLE" },
            // Read by nerfstudio from its command line, not from here; recorded so the
            // file says what the depth PNGs hold.
            "depth_unit_scale_factor": 0.001,
            "frames": list,
        });
        // Points on the true surface, in the poses' world frame: what splatfacto starts its
        // Gaussians from when the transforms name them.
        if let Some(points) = sample.file("points.ply") {
            job.placer
                .place(dataset, points, &scene.join("points.ply"))?;
            transforms["ply_file_path"] = json!("points.ply");
        }
        let mut bytes = serde_json::to_vec_pretty(&transforms)?;
        bytes.push(b'\n');
        job.placer.write(&scene.join("transforms.json"), &bytes)?;
    }
    Ok(json!({
        "layout": "{sample:06}/transforms.json with images/, depth/ (16-bit mm), masks/",
        "depth_mm": png16::depth_record(&job.summary),
        "nerfstudio_arguments": "nerfstudio-data --orientation-method none --center-method none --auto-scale-poses False keeps metric, z-up poses",
    }))
}
