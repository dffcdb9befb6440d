//! The contact sheet: the first samples and views of a recipe rendered small, one row per
//! (sample, view): RGB | depth (colour-mapped) | mask | part ids | instance ids | cracks.
//!
//! Owns: shrinking a recipe to preview size, the sheet's layout and its false colours. Must
//! not touch: the renderer or the encoders (it calls `pipeline::prepare`, `SampleRenderer` and
//! `output::rgb_png`), nor the recipe's files.

use crate::output::{ViewLayers, rgb_png};
use crate::pipeline::{SampleRenderer, for_each_image, prepare};
use crate::recipe::Recipe;
use anyhow::Result;
use rayon::prelude::*;

/// Pixels between the cells of the sheet, so neighbouring images do not run together.
pub const SEPARATOR: u32 = 2;
const SEPARATOR_COLOUR: [u8; 3] = [96, 96, 96];

/// How small to render the preview.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Size {
    /// A fraction of the recipe's resolution.
    Scale(f64),
    /// The longer side in pixels (never larger than the recipe's own resolution).
    MaxSide(u32),
}

/// Which samples and views a preview sheet shows, and how small.
#[derive(Clone, Copy, Debug)]
pub struct PreviewOptions {
    /// Samples from the start of the dataset (fewer if the dataset has fewer).
    pub samples: u64,
    /// Views of each sample; None takes up to four.
    pub views: Option<u32>,
    /// The size of each image.
    pub size: Size,
}

/// A rendered contact sheet.
pub struct Preview {
    pub png: Vec<u8>,
    pub samples: u64,
    pub views: u32,
    /// Size of one cell (one image of one view).
    pub width: u32,
    pub height: u32,
}

/// One column of the sheet.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Column {
    Rgb,
    Depth,
    Mask,
    Parts,
    Instances,
    Cracks,
}

/// The images of one (sample, view), still as raw buffers: depth is coloured only once the
/// whole sheet's depth range is known.
struct Row {
    rgb: Vec<u8>,
    depth: Vec<f32>,
    mask: Vec<u8>,
    parts: Vec<u32>,
    instances: Vec<u32>,
    cracks: Vec<u8>,
}

/// Shrinks `recipe` to the preview and renders its sheet (in parallel over samples and views).
pub fn render(recipe: &mut Recipe, options: &PreviewOptions) -> Result<Preview> {
    let (samples, views) = shrink(recipe, options);
    let recipe = &*recipe;
    let columns = columns(recipe);
    let rows: Vec<Row> = (0..samples)
        .into_par_iter()
        .map(|index| -> Result<Vec<Row>> {
            let sample = prepare(recipe, index)?;
            let renderer = SampleRenderer::new(&recipe.dataset, &sample);
            // One row per image: the clean view (if kept) and its augmented copies.
            (0..views)
                .into_par_iter()
                .map(|view| {
                    let mut rows = Vec::new();
                    for_each_image(&renderer, view, |layers, _, _| {
                        rows.push(row(layers, &columns));
                        Ok(())
                    })?;
                    Ok(rows)
                })
                .collect::<Result<Vec<Vec<Row>>>>()
                .map(|views| views.into_iter().flatten().collect())
        })
        .collect::<Result<Vec<Vec<Row>>>>()?
        .into_iter()
        .flatten()
        .collect();
    let camera = &recipe.dataset.camera;
    let (width, height) = (camera.width, camera.height);
    let (sheet_width, sheet_height, pixels) = compose(&rows, &columns, width, height);
    Ok(Preview {
        png: rgb_png(sheet_width, sheet_height, &pixels),
        samples,
        views,
        width,
        height,
    })
}

/// Cuts the dataset down to the preview's samples, views and resolution (aspect kept, at
/// least one pixel). The mesher follows the smaller pixels, so the preview also tessellates
/// less.
fn shrink(recipe: &mut Recipe, options: &PreviewOptions) -> (u64, u32) {
    let dataset = &mut recipe.dataset;
    let samples = options.samples.clamp(1, dataset.samples.max(1));
    let views = options
        .views
        .unwrap_or(4)
        .clamp(1, dataset.cameras_per_sample().max(1));
    let camera = &mut dataset.camera;
    let scale = match options.size {
        Size::Scale(s) => s,
        Size::MaxSide(px) => (f64::from(px) / f64::from(camera.width.max(camera.height))).min(1.0),
    };
    let scaled = |n: u32| ((f64::from(n) * scale).round() as u32).max(1);
    (camera.width, camera.height) = (scaled(camera.width), scaled(camera.height));
    (samples, views)
}

/// RGB, depth and mask always; the label columns the dataset asks for.
fn columns(recipe: &Recipe) -> Vec<Column> {
    let outputs = &recipe.dataset.outputs;
    let mut columns = vec![Column::Rgb, Column::Depth, Column::Mask];
    for (name, column) in [
        ("parts", Column::Parts),
        ("instances", Column::Instances),
        ("cracks", Column::Cracks),
    ] {
        if outputs.wants(name) {
            columns.push(column);
        }
    }
    columns
}

fn row(view: &dyn ViewLayers, columns: &[Column]) -> Row {
    let wanted = |c: Column| columns.contains(&c);
    Row {
        rgb: view.rgb().to_vec(),
        depth: view.depth().to_vec(),
        mask: view.mask(),
        parts: if wanted(Column::Parts) {
            view.part_ids()
        } else {
            Vec::new()
        },
        instances: if wanted(Column::Instances) {
            view.instance_ids()
        } else {
            Vec::new()
        },
        cracks: if wanted(Column::Cracks) {
            view.cracks().to_vec()
        } else {
            Vec::new()
        },
    }
}

/// Lays the rows out into one RGB8 image; returns (width, height, pixels).
fn compose(rows: &[Row], columns: &[Column], width: u32, height: u32) -> (u32, u32, Vec<u8>) {
    let (sheet_width, sheet_height) =
        sheet_size(columns.len() as u32, rows.len() as u32, width, height);
    let mut pixels = SEPARATOR_COLOUR.repeat((sheet_width * sheet_height) as usize);
    let range = depth_range(rows);
    for (r, row) in rows.iter().enumerate() {
        for (c, &column) in columns.iter().enumerate() {
            let origin = (
                c as u32 * (width + SEPARATOR),
                r as u32 * (height + SEPARATOR),
            );
            let cell = cell(row, column, range);
            for y in 0..height {
                let src = (y * width) as usize;
                let dst = ((origin.1 + y) * sheet_width + origin.0) as usize;
                for x in 0..width as usize {
                    pixels[3 * (dst + x)..3 * (dst + x) + 3].copy_from_slice(&cell[src + x]);
                }
            }
        }
    }
    (sheet_width, sheet_height, pixels)
}

/// Size of a sheet of `columns` × `rows` cells of `width` × `height` with separators between.
fn sheet_size(columns: u32, rows: u32, width: u32, height: u32) -> (u32, u32) {
    let span = |n: u32, size: u32| n * size + n.saturating_sub(1) * SEPARATOR;
    (span(columns, width), span(rows, height))
}

/// One cell's pixels.
fn cell(row: &Row, column: Column, depth_range: (f32, f32)) -> Vec<[u8; 3]> {
    match column {
        Column::Rgb => row
            .rgb
            .chunks_exact(3)
            .map(|p| [p[0], p[1], p[2]])
            .collect(),
        Column::Depth => row
            .depth
            .iter()
            .map(|&z| depth_colour(z, depth_range))
            .collect(),
        Column::Mask => row.mask.iter().map(|&m| [m; 3]).collect(),
        Column::Parts => row.parts.iter().map(|&id| id_colour(id)).collect(),
        Column::Instances => row.instances.iter().map(|&id| id_colour(id)).collect(),
        Column::Cracks => row.cracks.iter().map(|&m| [m; 3]).collect(),
    }
}

/// Nearest and farthest surface depth over the whole sheet, so colours compare across rows.
fn depth_range(rows: &[Row]) -> (f32, f32) {
    rows.iter()
        .flat_map(|r| r.depth.iter().copied())
        .filter(|&z| z > 0.0)
        .fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), z| {
            (lo.min(z), hi.max(z))
        })
}

/// Turbo colour of a depth, near = red, far = blue; no surface (0) stays black. Both ends of
/// Turbo are nearly black, so depths use the part from 0.1 (far) to 0.95 (near) and stay
/// distinct from the background.
fn depth_colour(z: f32, (near, far): (f32, f32)) -> [u8; 3] {
    if z <= 0.0 {
        return [0; 3];
    }
    let t = if far > near {
        (far - z) / (far - near)
    } else {
        1.0
    };
    turbo(0.1 + 0.85 * f64::from(t))
}

/// Google's Turbo colour map (Mikhailov 2019) by its published polynomial fit (Ruofei Du),
/// `x` in [0, 1] from blue to red.
fn turbo(x: f64) -> [u8; 3] {
    const RED: [f64; 6] = [
        0.13572138,
        4.61539260,
        -42.66032258,
        132.13108234,
        -152.94239396,
        59.28637943,
    ];
    const GREEN: [f64; 6] = [
        0.09140261,
        2.19418839,
        4.84296658,
        -14.18503333,
        4.27729857,
        2.82956604,
    ];
    const BLUE: [f64; 6] = [
        0.10667330,
        12.64194608,
        -60.58204836,
        110.36276771,
        -89.90310912,
        27.34824973,
    ];
    let x = x.clamp(0.0, 1.0);
    let channel = |c: &[f64; 6]| {
        let v = c.iter().rev().fold(0.0, |acc, k| acc * x + k);
        (v.clamp(0.0, 1.0) * 255.0).round() as u8
    };
    [channel(&RED), channel(&GREEN), channel(&BLUE)]
}

/// A deterministic, well-spread colour for a label id (0 = background = black): hues step by
/// the golden angle so consecutive ids never look alike.
fn id_colour(id: u32) -> [u8; 3] {
    if id == 0 {
        return [0; 3];
    }
    let hue = (f64::from(id) * 0.618_033_988_749_895).fract() * 6.0;
    // Alternate the brightness too, so ids whose hues come close still differ.
    let (s, v) = if id.is_multiple_of(2) {
        (0.55, 1.0)
    } else {
        (0.8, 0.85)
    };
    let f = hue.fract();
    let (p, q, t) = (v * (1.0 - s), v * (1.0 - s * f), v * (1.0 - s * (1.0 - f)));
    let rgb = match hue as u32 {
        0 => [v, t, p],
        1 => [q, v, p],
        2 => [p, v, t],
        3 => [p, q, v],
        4 => [t, p, v],
        _ => [v, p, q],
    };
    rgb.map(|c| (c * 255.0).round() as u8)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn turbo_runs_from_dark_blue_to_dark_red() {
        let [r0, _, b0] = turbo(0.1);
        assert!(b0 > r0, "far end is blue: {:?}", turbo(0.1));
        let [r1, _, b1] = turbo(0.95);
        assert!(r1 > 150 && b1 < 40, "near end is red: {:?}", turbo(0.95));
        // The middle of Turbo is a light green-yellow.
        let [_, g, _] = turbo(0.5);
        assert!(g > 200, "{:?}", turbo(0.5));
    }

    #[test]
    fn depth_colours_keep_background_black_and_surfaces_visible() {
        assert_eq!(depth_colour(0.0, (1.0, 2.0)), [0; 3]);
        for z in [1.0, 1.5, 2.0] {
            let c = depth_colour(z, (1.0, 2.0));
            assert!(
                c.iter().map(|&v| u32::from(v)).sum::<u32>() > 60,
                "{z}: {c:?}"
            );
        }
        assert_ne!(depth_colour(1.0, (1.0, 2.0)), depth_colour(2.0, (1.0, 2.0)));
        // A flat scene (one depth) still gets a colour.
        assert_ne!(depth_colour(3.0, (3.0, 3.0)), [0; 3]);
    }

    #[test]
    fn label_colours_are_distinct_and_background_is_black() {
        assert_eq!(id_colour(0), [0; 3]);
        let colours: Vec<[u8; 3]> = (1..=64).map(id_colour).collect();
        for (i, a) in colours.iter().enumerate() {
            assert_ne!(*a, [0; 3]);
            for b in &colours[i + 1..] {
                let d: i32 = a
                    .iter()
                    .zip(b)
                    .map(|(&x, &y)| (x as i32 - y as i32).abs())
                    .sum();
                assert!(d > 8, "ids {i} and another look alike: {a:?} {b:?}");
            }
        }
    }

    #[test]
    fn sheet_size_counts_separators_between_cells_only() {
        assert_eq!(sheet_size(1, 1, 10, 20), (10, 20));
        assert_eq!(
            sheet_size(3, 2, 10, 20),
            (30 + 2 * SEPARATOR, 40 + SEPARATOR)
        );
    }
}
