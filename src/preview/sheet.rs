//! The contact sheet: the first samples and views of a recipe rendered small, one row per
//! image (a view, or an augmented copy of it) and one column per layer the recipe writes, with
//! a header, column titles, row labels and a legend for every false-colour column, in a PNG
//! that fits a screen (at most `MAX_WIDTH` × `MAX_HEIGHT`).
//!
//! Owns: shrinking a recipe to preview size, choosing the cell size and how many rows fit, the
//! sheet's layout and what each cell shows. Must not touch: the renderer or the encoders (it
//! calls `pipeline::prepare`, `SampleRenderer` and `output::rgb_png`), nor the recipe's files.
//!
//! Fitting: cells keep the recipe's aspect and are never larger than `--size`; they shrink so
//! that every column fits the width and, down to `MIN_CELL` pixels high, so that every row
//! fits the height. Rows that still do not fit are left out (from the end: the last samples
//! and views) and the header says how many; only the rows shown are rendered.

use super::canvas::{Canvas, GLYPH, Rgb, clipped, fitting_scale, text_width, wrapped};
use super::colours::{flow_colour, id_colour, normal_colour};
use super::legend::{self, Legend, bar_colour};
use crate::build::BuiltSample;
use crate::output::{Flow, ViewLayers, rgb_png};
use crate::pipeline::{DamageClass, SampleRenderer, for_each_image, prepare};
use crate::recipe::Recipe;
use crate::scene::{DatasetSpec, Structure};
use anyhow::Result;
use rayon::prelude::*;
use std::collections::HashMap;
use std::sync::Arc;

/// Pixels between the cells of the sheet, so neighbouring images do not run together.
pub const SEPARATOR: u32 = 2;
/// The largest sheet: a full-HD screen.
pub const MAX_WIDTH: u32 = 1920;
pub const MAX_HEIGHT: u32 = 1080;
/// Cells shrink to fit every row down to this height (or the recipe's, if smaller); below it
/// rows are left out instead, as a smaller image would show nothing.
const MIN_CELL: u32 = 64;

const BACKGROUND: Rgb = [40, 40, 40];
const INK: Rgb = [235, 235, 235];
/// A cell that says something instead of showing an image.
const NOTE_FILL: Rgb = [72, 72, 72];
const PAD: u32 = 6;
/// Scale of the sheet's text: 16-pixel glyphs, readable on a full-HD screen.
const TEXT_SCALE: u32 = 2;
/// Height of a line of text at `TEXT_SCALE`, with its spacing.
const LINE: u32 = 20;
const HEADER_HEIGHT: u32 = 2 * LINE + PAD;
const TITLES_HEIGHT: u32 = LINE + 2;
/// Height of the legend strip (when any column needs a legend).
const LEGEND_STRIP: u32 = legend::HEIGHT + 2 * PAD;

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
    /// The largest size of each image (smaller when the sheet would not fit a screen).
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
    /// Images (rows) the samples and views have, clean and augmented.
    pub images: u64,
    /// Images the sheet shows: the first ones, as many as fit.
    pub shown: u64,
}

/// One column of the sheet: a per-view output, in the order the sheet shows them (images,
/// distances, masks, labels, vectors).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Layer {
    Rgb,
    RestRgb,
    Depth,
    RestDepth,
    RayDistance,
    Mask,
    Valid,
    Erased,
    Parts,
    Instances,
    Cracks,
    Normals,
    Flow,
    /// The flow from a frame of a sequence to the next.
    FrameFlow,
    /// The pixels where a sequence's tracked points are seen in this frame.
    PointTracks,
    Displacement,
    Damage,
}

/// Every column the sheet can show, in the sheet's order: the layer, its name in
/// `dataset.outputs` and its title.
const COLUMNS: [(Layer, &str, &str); 17] = [
    (Layer::Rgb, "rgb", "RGB"),
    (Layer::RestRgb, "rest_rgb", "rest RGB"),
    (Layer::Depth, "depth", "depth"),
    (Layer::RestDepth, "rest_depth", "rest depth"),
    (Layer::RayDistance, "ray_distance", "ray distance"),
    (Layer::Mask, "mask", "mask"),
    (Layer::Valid, "valid", "valid"),
    (Layer::Erased, "erased", "erased"),
    (Layer::Parts, "parts", "parts"),
    (Layer::Instances, "instances", "instances"),
    (Layer::Cracks, "cracks", "cracks"),
    (Layer::Normals, "normals", "normals"),
    (Layer::Flow, "flow", "flow"),
    (Layer::FrameFlow, "frame_flow", "flow to next frame"),
    (Layer::PointTracks, "point_tracks", "tracked points"),
    (Layer::Displacement, "displacement", "displacement"),
    (Layer::Damage, "damage", "damage class"),
];

impl Layer {
    fn column(self) -> &'static (Layer, &'static str, &'static str) {
        COLUMNS
            .iter()
            .find(|c| c.0 == self)
            .expect("every layer is in COLUMNS")
    }

    /// Its name in `dataset.outputs`.
    fn output(self) -> &'static str {
        self.column().1
    }

    /// Its column title.
    fn title(self) -> &'static str {
        self.column().2
    }

    /// Whether its values are metres along a ray (one colour bar serves them all).
    fn is_metres(self) -> bool {
        matches!(self, Layer::Depth | Layer::RestDepth | Layer::RayDistance)
    }

    /// What a cell of this mask says instead of an all-black image.
    fn empty_note(self) -> &'static str {
        match self {
            Layer::Mask => "no structure",
            Layer::Valid => "nothing valid",
            Layer::Erased => "nothing erased",
            Layer::Cracks => "no cracks",
            Layer::Flow | Layer::FrameFlow => "no flow",
            Layer::PointTracks => "no point seen",
            _ => "empty",
        }
    }

    /// The view's pixels of this layer.
    fn take(self, view: &dyn ViewLayers, names: &SampleNames) -> Cell {
        match self {
            Layer::Rgb => Cell::Colour(view.rgb().to_vec()),
            Layer::RestRgb => Cell::Colour(view.rest_rgb().to_vec()),
            Layer::Depth => Cell::Metres(view.depth().to_vec()),
            Layer::RestDepth => Cell::Metres(view.rest_depth().to_vec()),
            Layer::RayDistance => Cell::Metres(view.ray_distance()),
            Layer::Mask => Cell::Mask(view.mask()),
            Layer::Valid => Cell::Mask(view.valid()),
            Layer::Erased => Cell::Mask(view.erased()),
            Layer::Cracks => Cell::Mask(view.cracks().to_vec()),
            Layer::Parts => Cell::Labels(view.part_ids(), names.parts.clone()),
            Layer::Instances => Cell::Labels(view.instance_ids(), names.instances.clone()),
            Layer::Damage => Cell::Labels(
                view.damage().class.into_iter().map(u32::from).collect(),
                names.damage.clone(),
            ),
            Layer::Normals => Cell::Normals(view.normals()),
            Layer::Flow => Cell::Flow(view.flow()),
            Layer::FrameFlow => Cell::Flow(view.frame_flow().next),
            Layer::PointTracks => Cell::Mask(seen_points(view)),
            Layer::Displacement => Cell::Displacement(
                view.displacement(),
                view.depth().iter().map(|&z| z > 0.0).collect(),
            ),
        }
    }
}

/// 255 at the pixels holding a tracked point seen in this frame, 0 elsewhere.
fn seen_points(view: &dyn ViewLayers) -> Vec<u8> {
    let (width, height) = view.size();
    let mut mask = vec![0; width as usize * height as usize];
    for [x, y, state] in view.point_tracks() {
        let (col, row) = (x.floor(), y.floor());
        let inside =
            (0.0..f64::from(width)).contains(&col) && (0.0..f64::from(height)).contains(&row);
        if state == 1.0 && inside {
            mask[row as usize * width as usize + col as usize] = 255;
        }
    }
    mask
}

/// The raw pixels of one cell; colours are chosen once the whole sheet's ranges are known.
enum Cell {
    Colour(Vec<u8>),
    Metres(Vec<f32>),
    /// 255 = yes, 0 = no.
    Mask(Vec<u8>),
    /// Ids and the sample's name of each id (index = id).
    Labels(Vec<u32>, Arc<Vec<String>>),
    Normals(Vec<[f32; 3]>),
    Flow(Flow),
    /// Displacement vectors (metres) and whether each pixel sees a surface.
    Displacement(Vec<[f32; 3]>, Vec<bool>),
}

/// The names of a sample's part and instance ids (index = id, 0 = background).
struct SampleNames {
    parts: Arc<Vec<String>>,
    instances: Arc<Vec<String>>,
    /// The damage classes by value (0 = none).
    damage: Arc<Vec<String>>,
}

impl SampleNames {
    /// As the sample's record names them: parts by name, instances by id and structure name
    /// (two structures may share a name, never an id).
    fn of(sample: &BuiltSample) -> Self {
        let parts = std::iter::once("background".to_string())
            .chain(sample.parts.iter().cloned())
            .collect();
        let structures = &sample.scene.structures;
        let mut instances = vec!["background".to_string()];
        instances.extend(structures.iter().enumerate().map(|(i, s)| match s {
            Structure::Beam(_) => format!("{} beam", i + 1),
            Structure::Assembly(a) => format!("{} {}", i + 1, a.name),
            Structure::Frame(f) => format!("{} {}", i + 1, f.name),
        }));
        if sample.ground.is_some() {
            instances.push(format!("{} ground", structures.len() + 1));
        }
        SampleNames {
            parts: Arc::new(parts),
            instances: Arc::new(instances),
            damage: Arc::new(DamageClass::NAMES.map(String::from).to_vec()),
        }
    }
}

/// One image of the sheet: which it is and its cells, one per column.
struct Row {
    sample: u64,
    view: u32,
    /// The augmented copy (from 0), None for the clean view.
    copy: Option<u32>,
    cells: Vec<Cell>,
}

/// Shrinks `recipe` to the preview and renders its sheet (in parallel over samples and views).
pub fn render(recipe: &mut Recipe, options: &PreviewOptions) -> Result<Preview> {
    let drawn = draw(recipe, options)?;
    let canvas = &drawn.canvas;
    Ok(Preview {
        png: rgb_png(canvas.width(), canvas.height(), canvas.pixels()),
        samples: drawn.samples,
        views: drawn.views,
        width: drawn.plan.cell.0,
        height: drawn.plan.cell.1,
        images: drawn.images,
        shown: drawn.plan.rows,
    })
}

/// A drawn sheet with what went into it (the layout, layers and rows for the tests, which
/// check the pixels against the rendered values).
#[cfg_attr(not(test), allow(dead_code))]
struct Drawn {
    canvas: Canvas,
    samples: u64,
    views: u32,
    images: u64,
    plan: Plan,
    layout: Layout,
    layers: Vec<Layer>,
    rows: Vec<Row>,
}

/// Plans the sheet, renders the rows it shows and draws it.
fn draw(recipe: &mut Recipe, options: &PreviewOptions) -> Result<Drawn> {
    let (samples, views) = shrink(recipe, options);
    let layers = layers(&recipe.dataset);
    let augment = &recipe.dataset.augment;
    let per_view = augment.per_view().max(1);
    let images = samples * u64::from(views) * u64::from(per_view);
    let labels = label_width(samples, views, augment.copies);
    let legends = layers.iter().any(|&l| needs_legend(l));
    let camera = &mut recipe.dataset.camera;
    let plan = plan(
        layers.len() as u32,
        images,
        (camera.width, camera.height),
        labels,
        legends,
    );
    (camera.width, camera.height) = plan.cell;
    let rows = render_rows(recipe, &layers, plan.rows, views, per_view)?;
    let header = header(&recipe.dataset, samples, views, images, &plan);
    let least = header.iter().map(|l| text_width(l, 1)).max().unwrap_or(0) + 2 * PAD;
    let columns = layers.len() as u32;
    let layout = Layout::new(&plan, columns, labels, legend_count(&layers), least);
    let canvas = Sheet {
        dataset: &recipe.dataset,
        layers: &layers,
        rows: &rows,
        layout: &layout,
        header: &header,
    }
    .draw();
    Ok(Drawn {
        canvas,
        samples,
        views,
        images,
        plan,
        layout,
        layers,
        rows,
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

/// The per-view layers the dataset writes, in the sheet's order. A dataset that writes none
/// (meshes or points only) still gets its RGB, so the sheet shows what was drawn.
fn layers(dataset: &DatasetSpec) -> Vec<Layer> {
    let written: Vec<Layer> = COLUMNS
        .iter()
        .map(|c| c.0)
        .filter(|l| dataset.outputs.wants(l.output()))
        .collect();
    if written.is_empty() {
        vec![Layer::Rgb]
    } else {
        written
    }
}

/// Whether a column's colours need a legend (the photographs and masks do not).
fn needs_legend(layer: Layer) -> bool {
    layer.is_metres()
        || matches!(
            layer,
            Layer::Parts
                | Layer::Instances
                | Layer::Damage
                | Layer::Normals
                | Layer::Flow
                | Layer::FrameFlow
                | Layer::Displacement
        )
}

/// Legend boxes: one colour bar for all the metre columns, one for each other that needs one.
fn legend_count(layers: &[Layer]) -> u32 {
    let metres = layers.iter().any(|l| l.is_metres());
    let others = layers
        .iter()
        .filter(|&&l| needs_legend(l) && !l.is_metres())
        .count();
    u32::from(metres) + others as u32
}

/// Width of the row labels' column: the longest label line at the sheet's text scale.
fn label_width(samples: u64, views: u32, copies: u32) -> u32 {
    let mut lines = vec![
        format!("sample {}", samples.saturating_sub(1)),
        format!("view {}", views.saturating_sub(1)),
    ];
    if copies > 0 {
        lines.push(format!("copy {copies} of {copies}"));
    }
    let longest = lines
        .iter()
        .map(|l| text_width(l, TEXT_SCALE))
        .max()
        .unwrap_or(0);
    longest + 2 * PAD
}

/// The size of every cell, how many rows (images) the sheet shows and in how many blocks side
/// by side.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Plan {
    cell: (u32, u32),
    rows: u64,
    blocks: u32,
    /// Rows in each block (the last may have fewer).
    per_block: u32,
}

/// Most blocks of rows side by side.
const MAX_BLOCKS: u32 = 8;
/// Pixels between two blocks.
const BLOCK_GAP: u32 = 3 * PAD;

/// Fits `columns` × `images` cells of at most `frame` pixels (with the row labels and, if
/// any, the legends) into `MAX_WIDTH` × `MAX_HEIGHT`: rows that do not fit one under another
/// continue in blocks side by side when the width allows. Of the layouts, the one showing the
/// most rows, then with the largest cells, then with the fewest blocks; see the module's doc.
fn plan(columns: u32, images: u64, frame: (u32, u32), labels: u32, legends: bool) -> Plan {
    let mut best =
        plan_in_blocks(1, columns, images, frame, labels, legends).expect("one block always fits");
    for blocks in 2..=MAX_BLOCKS {
        if let Some(plan) = plan_in_blocks(blocks, columns, images, frame, labels, legends)
            && (plan.rows, plan.cell.1) > (best.rows, best.cell.1)
        {
            best = plan;
        }
    }
    best
}

/// The layout in `blocks` blocks side by side; None when more than one block would need
/// cells smaller than `MIN_CELL` (or than the frame, if smaller).
fn plan_in_blocks(
    blocks: u32,
    columns: u32,
    images: u64,
    frame: (u32, u32),
    labels: u32,
    legends: bool,
) -> Option<Plan> {
    let (w, h) = (f64::from(frame.0.max(1)), f64::from(frame.1.max(1)));
    let block = (MAX_WIDTH + BLOCK_GAP) / blocks - BLOCK_GAP;
    let across = block.saturating_sub(labels + SEPARATOR) / columns.max(1);
    let width_fit = (f64::from(across.saturating_sub(SEPARATOR)) / w).min(1.0);
    let smallest = f64::from(MIN_CELL.min(frame.1.max(1)));
    if blocks > 1 && h * width_fit < smallest {
        return None;
    }
    let room = MAX_HEIGHT - HEADER_HEIGHT - TITLES_HEIGHT - if legends { LEGEND_STRIP } else { 0 };
    let per_block = images.div_ceil(u64::from(blocks)).max(1);
    let every_row = f64::from(room) / per_block as f64 - f64::from(SEPARATOR);
    let height = (h * width_fit).min(every_row.max(smallest));
    let scale = height / h;
    // A hair over the product, so that an exact fit is not lost to rounding down.
    let side = |n: f64| ((n * scale + 1e-9).floor() as u32).max(1);
    let cell = (side(w), side(h));
    let per_block = per_block.min(u64::from(room / (cell.1 + SEPARATOR)).max(1)) as u32;
    let rows = images.min(u64::from(per_block) * u64::from(blocks));
    // Blocks the rows shown actually fill.
    let blocks = rows.div_ceil(u64::from(per_block)) as u32;
    Some(Plan {
        cell,
        rows,
        blocks,
        per_block,
    })
}

/// Renders the first `rows` images: whole samples in parallel, and in each the views needed.
fn render_rows(
    recipe: &Recipe,
    layers: &[Layer],
    rows: u64,
    views: u32,
    per_view: u32,
) -> Result<Vec<Row>> {
    let pairs = rows.div_ceil(u64::from(per_view));
    let samples = pairs.div_ceil(u64::from(views));
    let mut rendered: Vec<Row> = (0..samples)
        .into_par_iter()
        .map(|index| -> Result<Vec<Row>> {
            let sample = prepare(recipe, index)?;
            let names = SampleNames::of(&sample);
            let renderer = SampleRenderer::new(&recipe.dataset, &sample).for_preview();
            let needed = (pairs - index * u64::from(views)).min(u64::from(views)) as u32;
            // One row per image: the clean view (if kept) and its augmented copies.
            (0..needed)
                .into_par_iter()
                .map(|view| {
                    let mut rows = Vec::new();
                    for_each_image(&renderer, view, |image, copy, _| {
                        let cells = layers.iter().map(|l| l.take(image, &names)).collect();
                        rows.push(Row {
                            sample: index,
                            view,
                            copy,
                            cells,
                        });
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
    rendered.truncate(rows as usize);
    Ok(rendered)
}

/// Where everything lies on the sheet.
#[derive(Clone, Copy, Debug)]
struct Layout {
    width: u32,
    height: u32,
    /// Width of the row labels' column.
    labels: u32,
    cell: (u32, u32),
    /// Blocks side by side, the rows in each, and a block's width.
    blocks: u32,
    per_block: u32,
    block_width: u32,
}

impl Layout {
    /// The layout of `plan`, at least `least` wide (the header's width at the font's size).
    fn new(plan: &Plan, columns: u32, labels: u32, legends: u32, least: u32) -> Self {
        let block_width = labels + SEPARATOR + columns * (plan.cell.0 + SEPARATOR);
        let grid = plan.blocks * (block_width + BLOCK_GAP) - BLOCK_GAP;
        let legend_row = legends * (legend::WIDTH + PAD) + PAD;
        let strip = if legends > 0 { LEGEND_STRIP } else { 0 };
        Layout {
            width: grid.max(legend_row).max(least).min(MAX_WIDTH),
            height: HEADER_HEIGHT
                + TITLES_HEIGHT
                + plan.per_block * (plan.cell.1 + SEPARATOR)
                + strip,
            labels,
            cell: plan.cell,
            blocks: plan.blocks,
            per_block: plan.per_block,
            block_width,
        }
    }

    /// Left edge of block `b`.
    fn block_left(&self, block: u32) -> u32 {
        block * (self.block_width + BLOCK_GAP)
    }

    /// Top-left corner of cell (column, row); rows fill a block top to bottom, then the next.
    fn cell_at(&self, column: u32, row: u32) -> (u32, u32) {
        let (block, row) = (row / self.per_block, row % self.per_block);
        (
            self.block_left(block) + self.labels + SEPARATOR + column * (self.cell.0 + SEPARATOR),
            HEADER_HEIGHT + TITLES_HEIGHT + row * (self.cell.1 + SEPARATOR),
        )
    }

    /// Top of the column titles' strip.
    fn titles_top(&self) -> u32 {
        HEADER_HEIGHT
    }

    /// Top-left corner of legend box `i`.
    fn legend_at(&self, i: u32) -> (u32, u32) {
        let top = HEADER_HEIGHT + TITLES_HEIGHT + self.per_block * (self.cell.1 + SEPARATOR) + PAD;
        (PAD + i * (legend::WIDTH + PAD), top)
    }
}

/// The value ranges the whole sheet shares, so a colour means the same in every row.
struct Ranges {
    /// Nearest and farthest distance over every metre column, if any surface is seen.
    metres: Option<(f32, f32)>,
    /// Largest flow (pixels) and displacement (metres) magnitude.
    flow: f32,
    displacement: f32,
    /// Per label column: each name's slot (colour id_colour(slot + 1)), in order of first
    /// appearance over the rows.
    names: HashMap<usize, Vec<String>>,
}

impl Ranges {
    fn of(rows: &[Row]) -> Self {
        let mut ranges = Ranges {
            metres: None,
            flow: 0.0,
            displacement: 0.0,
            names: HashMap::new(),
        };
        for row in rows {
            for (column, cell) in row.cells.iter().enumerate() {
                ranges.include(column, cell);
            }
        }
        ranges
    }

    fn include(&mut self, column: usize, cell: &Cell) {
        let finite_max = |m: f32, v: f32| if v.is_finite() { m.max(v) } else { m };
        match cell {
            Cell::Metres(values) => {
                for &z in values.iter().filter(|z| **z > 0.0 && z.is_finite()) {
                    let (lo, hi) = self.metres.unwrap_or((z, z));
                    self.metres = Some((lo.min(z), hi.max(z)));
                }
            }
            Cell::Flow(flow) => {
                for (v, _) in flow
                    .vectors
                    .iter()
                    .zip(&flow.valid)
                    .filter(|(_, m)| **m != 0)
                {
                    self.flow = finite_max(self.flow, v[0].hypot(v[1]));
                }
            }
            Cell::Displacement(vectors, seen) => {
                for (d, _) in vectors.iter().zip(seen).filter(|(_, s)| **s) {
                    self.displacement = finite_max(self.displacement, length(*d));
                }
            }
            Cell::Labels(ids, names) => {
                let slots = self.names.entry(column).or_default();
                for &id in ids.iter().filter(|&&id| id != 0) {
                    let name = label_name(names, id);
                    if !slots.contains(&name) {
                        slots.push(name);
                    }
                }
            }
            Cell::Colour(_) | Cell::Mask(_) | Cell::Normals(_) => {}
        }
    }
}

fn length(d: [f32; 3]) -> f32 {
    (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt()
}

/// The name of label `id`, or its number when the sample's table has no such id.
fn label_name(names: &[String], id: u32) -> String {
    names
        .get(id as usize)
        .cloned()
        .unwrap_or_else(|| format!("id {id}"))
}

/// Colour of a depth-like distance `z` given the sheet's (near, far): the bar's colour at
/// z's place along it; no surface (0) stays black.
fn metres_colour(z: f32, range: Option<(f32, f32)>) -> Rgb {
    match range {
        Some((near, far)) if z > 0.0 && z.is_finite() => {
            let t = if far > near {
                (z - near) / (far - near)
            } else {
                0.0
            };
            bar_colour(f64::from(t), true)
        }
        _ => [0; 3],
    }
}

/// Displacement in millimetres when the largest is under a metre, else in metres.
fn displacement_unit(max: f32) -> (&'static str, f64) {
    if max < 1.0 {
        ("mm", 1000.0)
    } else {
        ("m", 1.0)
    }
}

/// Two lines: what the sheet is a preview of, and how much of it is shown.
fn header(
    dataset: &DatasetSpec,
    samples: u64,
    views: u32,
    images: u64,
    plan: &Plan,
) -> [String; 2] {
    let augment = &dataset.augment;
    let copies = match (augment.copies, augment.keep_clean) {
        (0, _) => String::new(),
        (k, true) => format!(", each with {k} augmented copies"),
        (k, false) => format!(", {k} augmented copies each (no clean view)"),
    };
    let first = format!(
        "{}: {samples} samples × {views} views{copies}",
        dataset.name
    );
    let ((w, h), shown) = (plan.cell, plan.rows);
    let second = if shown == images {
        format!("all {images} images shown, cells {w}×{h} px")
    } else {
        format!(
            "{shown} of {images} images shown ({} left out to fit {MAX_WIDTH}×{MAX_HEIGHT}: fewer --samples/--views), cells {w}×{h} px",
            images - shown
        )
    };
    [first, second]
}

/// Everything drawn on one sheet.
struct Sheet<'a> {
    dataset: &'a DatasetSpec,
    layers: &'a [Layer],
    rows: &'a [Row],
    layout: &'a Layout,
    header: &'a [String; 2],
}

impl Sheet<'_> {
    fn draw(&self) -> Canvas {
        let layout = self.layout;
        let mut canvas = Canvas::new(layout.width, layout.height, BACKGROUND);
        let ranges = Ranges::of(self.rows);
        self.header(&mut canvas);
        self.titles(&mut canvas);
        for (r, row) in self.rows.iter().enumerate() {
            self.label(&mut canvas, r as u32, row);
            for (c, (&layer, cell)) in self.layers.iter().zip(&row.cells).enumerate() {
                let (x, y) = layout.cell_at(c as u32, r as u32);
                self.cell(&mut canvas, (x, y), layer, (c, cell), &ranges);
            }
        }
        for (i, legend) in self.legends(&ranges).iter().enumerate() {
            let (x, y) = layout.legend_at(i as u32);
            legend::draw(&mut canvas, x, y, legend);
        }
        canvas
    }

    /// The header's two lines, as large as they fit.
    fn header(&self, canvas: &mut Canvas) {
        for (i, text) in self.header.iter().enumerate() {
            let width = canvas.width() - 2 * PAD;
            let scale = fitting_scale(text, width, TEXT_SCALE);
            let top = PAD + i as u32 * LINE;
            canvas.text(PAD, top, &clipped(text, width, scale), scale, INK);
        }
    }

    /// Each column's title, centred over it in every block, all at one scale: the largest at
    /// which every title fits its cell, or else the font's own size on up to two lines.
    fn titles(&self, canvas: &mut Canvas) {
        let width = self.layout.cell.0;
        let scale = self
            .layers
            .iter()
            .map(|l| fitting_scale(l.title(), width, TEXT_SCALE))
            .min()
            .unwrap_or(1);
        for block in 0..self.layout.blocks {
            let first_row = block * self.layout.per_block;
            for (c, layer) in self.layers.iter().enumerate() {
                let (x, _) = self.layout.cell_at(c as u32, first_row);
                let top = self.layout.titles_top() + 2;
                centred(canvas, (x, top, width), layer.title(), scale, 2);
            }
        }
    }

    /// "sample S", "view V" and, for an augmented copy, "copy k of K" (k from 1), one under
    /// another at the sheet's text size, or at the font's own size if the row is too low;
    /// in one short line ("s0 v1 c2/2") if even that does not fit.
    fn label(&self, canvas: &mut Canvas, r: u32, row: &Row) {
        let (x, top) = self.layout.cell_at(0, r);
        let left = x - SEPARATOR - self.layout.labels + PAD;
        let copies = self.dataset.augment.copies;
        let mut lines = vec![
            format!("sample {}", row.sample),
            format!("view {}", row.view),
        ];
        if let Some(copy) = row.copy {
            lines.push(format!("copy {} of {copies}", copy + 1));
        }
        let room = self.layout.cell.1 + SEPARATOR;
        let n = lines.len() as u32;
        // n lines of glyphs and n - 1 gaps between them.
        let fits = |scale: u32, step: u32| (n - 1) * step + GLYPH * scale <= room;
        let (scale, step) = if fits(TEXT_SCALE, LINE) {
            (TEXT_SCALE, LINE)
        } else if fits(1, GLYPH + 1) {
            (1, GLYPH + 1)
        } else {
            let copy = row
                .copy
                .map_or(String::new(), |c| format!(" c{}/{copies}", c + 1));
            lines = vec![format!("s{} v{}{copy}", row.sample, row.view)];
            (1, GLYPH + 1)
        };
        let width = self.layout.labels - PAD;
        for (i, text) in lines.iter().enumerate() {
            let y = top + i as u32 * step;
            canvas.text(left, y, &clipped(text, width, scale), scale, INK);
        }
    }

    /// One cell: the layer's image, or a note where a mask is empty everywhere.
    fn cell(
        &self,
        canvas: &mut Canvas,
        (x, y): (u32, u32),
        layer: Layer,
        (column, cell): (usize, &Cell),
        ranges: &Ranges,
    ) {
        let (w, h) = self.layout.cell;
        if is_empty(cell) {
            canvas.fill(x, y, w, h, NOTE_FILL);
            let note = layer.empty_note();
            let scale = fitting_scale(note, w.saturating_sub(4), TEXT_SCALE);
            let lines = wrapped(note, w, scale).len() as u32;
            let top = y + h.saturating_sub(lines * GLYPH * scale + (lines - 1) * 2) / 2;
            centred(canvas, (x, top, w), note, scale, lines as usize);
            return;
        }
        canvas.paste(x, y, w, &pixels(cell, column, ranges));
    }

    /// The legend of every column that needs one, in column order.
    fn legends(&self, ranges: &Ranges) -> Vec<Legend> {
        let mut legends = Vec::new();
        let metres: Vec<&str> = self
            .layers
            .iter()
            .filter(|l| l.is_metres())
            .map(|l| l.title())
            .collect();
        for (column, &layer) in self.layers.iter().enumerate() {
            let legend = match layer {
                _ if layer.is_metres() => {
                    if metres.first() != Some(&layer.title()) {
                        continue;
                    }
                    let (low, high) = ranges.metres.unwrap_or((0.0, 0.0));
                    Legend::Bar {
                        title: format!("{}, m", metres.join(" · ")),
                        low: f64::from(low),
                        high: f64::from(high),
                        near_is_red: true,
                        note: if ranges.metres.is_some() {
                            "near = red; black: no surface".into()
                        } else {
                            "no surface in the views shown".into()
                        },
                    }
                }
                Layer::Displacement => {
                    let (unit, factor) = displacement_unit(ranges.displacement);
                    Legend::Bar {
                        title: format!("displacement |d|, {unit}"),
                        low: 0.0,
                        high: f64::from(ranges.displacement) * factor,
                        near_is_red: false,
                        note: "world axes; black: no surface".into(),
                    }
                }
                Layer::Normals => Legend::Normals(self.dataset.normals),
                Layer::Flow | Layer::FrameFlow => Legend::Flow { max: ranges.flow },
                Layer::Parts | Layer::Instances | Layer::Damage => Legend::Names {
                    title: layer.title(),
                    names: ranges.names.get(&column).cloned().unwrap_or_default(),
                },
                _ => continue,
            };
            legends.push(legend);
        }
        legends
    }
}

/// Draws `text` centred in the `width` from `x`, from `top` down, in at most `most` lines.
fn centred(
    canvas: &mut Canvas,
    (x, top, width): (u32, u32, u32),
    text: &str,
    scale: u32,
    most: usize,
) {
    for (i, line) in wrapped(text, width, scale).iter().take(most).enumerate() {
        let left = x + width.saturating_sub(text_width(line, scale)) / 2;
        let y = top + i as u32 * (GLYPH * scale + 2);
        canvas.text(left, y, line, scale, INK);
    }
}

/// Whether a cell has nothing to show: a mask 0 everywhere, or flow valid nowhere.
fn is_empty(cell: &Cell) -> bool {
    match cell {
        Cell::Mask(m) => m.iter().all(|&v| v == 0),
        Cell::Flow(flow) => flow.valid.iter().all(|&v| v == 0),
        _ => false,
    }
}

/// A cell's false colours.
fn pixels(cell: &Cell, column: usize, ranges: &Ranges) -> Vec<Rgb> {
    match cell {
        Cell::Colour(rgb) => rgb.chunks_exact(3).map(|p| [p[0], p[1], p[2]]).collect(),
        Cell::Metres(values) => values
            .iter()
            .map(|&z| metres_colour(z, ranges.metres))
            .collect(),
        Cell::Mask(mask) => mask.iter().map(|&m| [m; 3]).collect(),
        Cell::Labels(ids, names) => {
            let slots = ranges.names.get(&column).map(Vec::as_slice).unwrap_or(&[]);
            let slot: HashMap<&str, u32> = slots
                .iter()
                .enumerate()
                .map(|(i, n)| (n.as_str(), i as u32 + 1))
                .collect();
            ids.iter()
                .map(|&id| match id {
                    0 => [0; 3],
                    _ => id_colour(slot[label_name(names, id).as_str()]),
                })
                .collect()
        }
        Cell::Normals(normals) => normals.iter().map(|&n| normal_colour(n)).collect(),
        Cell::Flow(flow) => flow
            .vectors
            .iter()
            .zip(&flow.valid)
            .map(|(v, &ok)| match ok {
                0 => [0; 3],
                _ => flow_colour(v[0], v[1], ranges.flow),
            })
            .collect(),
        Cell::Displacement(vectors, seen) => {
            let max = f64::from(ranges.displacement);
            vectors
                .iter()
                .zip(seen)
                .map(|(&d, &s)| match s {
                    false => [0; 3],
                    true if max > 0.0 => bar_colour(f64::from(length(d)) / max, false),
                    true => bar_colour(0.0, false),
                })
                .collect()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::output::WRITERS;
    use font8x8::legacy::BASIC_LEGACY;

    /// Two structures (so instance ids differ), one of them with two parts. Pure blue
    /// background and no anti-aliasing: an RGB pixel is background exactly when no surface is
    /// there. `OUTPUTS` and `AUGMENT` are filled in by each test.
    const BLOCKS: &str = r#"dataset(#{
    name: "sheet",
    seed: 1,
    samples: 2,
    views: 2,
    outputs: OUTPUTS,
    background: [0.0, 0.0, 1.0],
    antialias: false,
    AUGMENT
    camera: #{ width: 64, height: 48, pitch: [deg(10), deg(60)] },
    scene: |rng| [
        assembly("block", [shape::box(rng.uniform(0.8, 1.2), 0.5, 0.3), shape::box(0.3, 0.3, 0.3).translate(0.0, 0.0, 0.3).part("cap")])
            .colour([0.8, 0.3, 0.2]),
        assembly("post", [shape::box(0.2, 0.2, 0.8).translate(0.9, 0.0, 0.0)]).colour([0.3, 0.7, 0.3]),
    ],
});
"#;

    /// A loaded beam: it bends, so flow and displacement are not zero.
    const BEAM: &str = r#"import "beam" as beam;
dataset(#{
    name: "beam",
    seed: 2,
    samples: 1,
    views: 2,
    outputs: OUTPUTS,
    antialias: false,
    camera: #{ width: 64, height: 64, pitch: [deg(10), deg(40)] },
    scene: |rng| beam::simply_supported(4.0, 0.2, 0.4, 2.0, 0.15),
});
"#;

    fn sheet(recipe: &str, outputs: &str, augment: &str, size: u32) -> Drawn {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("sheet.rhai");
        let text = recipe
            .replace("OUTPUTS", outputs)
            .replace("AUGMENT", augment);
        std::fs::write(&path, text).unwrap();
        let mut recipe = Recipe::load(&path, &[]).unwrap();
        let options = PreviewOptions {
            samples: 4,
            views: None,
            size: Size::MaxSide(size),
        };
        draw(&mut recipe, &options).unwrap()
    }

    /// `BLOCKS` with RGB, depth, mask, parts and instances, at 32 × 24 px.
    fn five_columns() -> Drawn {
        let outputs = r#"["rgb", "depth", "mask", "parts", "instances"]"#;
        sheet(BLOCKS, outputs, "", 32)
    }

    /// Where `text`, drawn at `scale` straight from the font's bitmaps (BASIC_LEGACY: byte =
    /// row, bit 0 = leftmost pixel), appears in the rectangle (x, y, width, height): lit
    /// pixels in the sheet's ink, the others not.
    fn find_text(canvas: &Canvas, area: (u32, u32, u32, u32), text: &str, scale: u32) -> bool {
        let glyphs: Vec<[u8; 8]> = text.bytes().map(|b| BASIC_LEGACY[b as usize]).collect();
        let (w, h) = (8 * scale * glyphs.len() as u32, 8 * scale);
        let lit = |x: u32, y: u32| {
            let (glyph, column) = ((x / scale / 8) as usize, (x / scale) % 8);
            glyphs[glyph][(y / scale) as usize] & (1 << column) != 0
        };
        let (x0, y0, aw, ah) = area;
        let right = (x0 + aw).min(canvas.width());
        let bottom = (y0 + ah).min(canvas.height());
        (y0..bottom.saturating_sub(h - 1)).any(|top| {
            (x0..right.saturating_sub(w - 1)).any(|left| {
                (0..h).all(|y| (0..w).all(|x| (canvas.get(left + x, top + y) == INK) == lit(x, y)))
            })
        })
    }

    /// The rectangle of row `r`'s label.
    fn label_area(layout: &Layout, r: usize) -> (u32, u32, u32, u32) {
        let (x, y) = layout.cell_at(0, r as u32);
        let height = layout.cell.1 + SEPARATOR;
        (
            x - SEPARATOR - layout.labels,
            y,
            layout.labels + SEPARATOR,
            height,
        )
    }

    /// The (x, y) pixel of cell (column, row), counting from the cell's corner.
    fn at(drawn: &Drawn, column: usize, row: usize, x: u32, y: u32) -> Rgb {
        let (left, top) = drawn.layout.cell_at(column as u32, row as u32);
        drawn.canvas.get(left + x, top + y)
    }

    #[test]
    fn every_per_view_output_has_a_column_and_every_column_an_output() {
        for writer in &WRITERS {
            assert!(
                COLUMNS.iter().any(|c| c.1 == writer.output),
                "{} has no column",
                writer.output
            );
        }
        for (layer, output, _) in COLUMNS {
            assert!(WRITERS.iter().any(|w| w.output == output), "{layer:?}");
            assert_eq!(
                COLUMNS.iter().filter(|c| c.0 == layer).count(),
                1,
                "{layer:?}"
            );
        }
    }

    #[test]
    fn sheets_fit_a_full_hd_screen_whatever_the_number_of_images() {
        for columns in [1, 3, 5, 14] {
            for images in [1, 16, 28, 400, 10_000, 100 * 100 * 1001] {
                for frame in [(960, 960), (240, 180), (4000, 300), (32, 24), (1, 1)] {
                    let labels = label_width(100, 100, 1000);
                    let fit = plan(columns, images, frame, labels, true);
                    let layout = Layout::new(&fit, columns, labels, 6, 1920);
                    let case = format!("{columns} columns, {images} images of {frame:?}");
                    assert!(
                        layout.width <= 1920 && layout.height <= 1080,
                        "{case}: {layout:?}"
                    );
                    assert!(fit.rows >= 1 && fit.rows <= images, "{case}: {fit:?}");
                    assert!(fit.cell.0 <= frame.0 && fit.cell.1 <= frame.1, "{case}");
                    // Every shown row has a place on the sheet.
                    let (_, bottom) = layout.cell_at(columns - 1, fit.per_block - 1);
                    assert!(bottom + fit.cell.1 <= layout.height, "{case}");
                    assert!(u64::from(fit.blocks * fit.per_block) >= fit.rows, "{case}");
                }
            }
        }
        // The default preview (4 samples × 4 views of RGB, depth and mask at 240 px) shows
        // every image, in cells no smaller than MIN_CELL.
        let default = plan(3, 16, (240, 240), label_width(4, 4, 0), true);
        assert_eq!(default.rows, 16);
        assert!(default.cell.1 >= MIN_CELL, "{default:?}");
        // 10⁴ images cannot all fit: rows are left out rather than shrunk below MIN_CELL.
        let many = plan(3, 10_000, (240, 240), label_width(100, 100, 0), true);
        assert!(many.rows < 10_000 && many.cell.1 >= MIN_CELL, "{many:?}");
    }

    #[test]
    fn columns_are_the_written_layers_under_their_titles() {
        let drawn = five_columns();
        assert_eq!(
            drawn.layers,
            [
                Layer::Rgb,
                Layer::Depth,
                Layer::Mask,
                Layer::Parts,
                Layer::Instances
            ]
        );
        let layout = &drawn.layout;
        let (w, strip) = (layout.cell.0, (layout.titles_top(), TITLES_HEIGHT));
        for (c, title) in ["RGB", "depth", "mask", "parts", "instances"]
            .iter()
            .enumerate()
        {
            let (x, _) = layout.cell_at(c as u32, 0);
            let found =
                (1..=2).any(|s| find_text(&drawn.canvas, (x, strip.0, w, strip.1), &title[..2], s));
            assert!(found, "the title {title} is not over column {c}");
        }
        // Nothing right of the last column in the first block: no sixth column.
        let (x, _) = layout.cell_at(4, 0);
        for y in strip.0..strip.0 + strip.1 {
            for x in x + w..layout.block_width.min(layout.width) {
                assert_eq!(drawn.canvas.get(x, y), BACKGROUND, "({x}, {y})");
            }
        }
        // Rows: 2 samples × 2 views, labelled.
        assert_eq!(drawn.rows.len(), 4);
        for (r, row) in drawn.rows.iter().enumerate() {
            let area = label_area(layout, r);
            let sample = format!("sample {}", row.sample);
            assert!(
                (1..=2).any(|s| find_text(&drawn.canvas, area, &sample, s)),
                "row {r} is not labelled {sample}"
            );
        }
    }

    #[test]
    fn cells_agree_with_each_other_and_depth_reads_off_its_bar() {
        let drawn = five_columns();
        let (w, h) = drawn.layout.cell;
        // The sheet's depth range, from the rendered depths themselves.
        let depths: Vec<f32> = drawn
            .rows
            .iter()
            .flat_map(|row| match &row.cells[1] {
                Cell::Metres(z) => z.clone(),
                _ => panic!("column 1 is depth"),
            })
            .filter(|&z| z > 0.0)
            .collect();
        let near = depths.iter().copied().fold(f32::INFINITY, f32::min);
        let far = depths.iter().copied().fold(0.0, f32::max);
        assert!(far > near);
        let (bx, by) = drawn.layout.legend_at(0);
        let bar: Vec<Rgb> = (0..legend::BAR_WIDTH)
            .map(|i| {
                drawn
                    .canvas
                    .get(bx + legend::BAR_LEFT + i, by + legend::BAR_TOP + 4)
            })
            .collect();
        let distance = |a: Rgb, b: Rgb| -> i32 {
            a.iter()
                .zip(b)
                .map(|(&x, y)| (i32::from(x) - i32::from(y)).abs())
                .sum()
        };
        let (mut surface, mut background) = (0, 0);
        for (r, row) in drawn.rows.iter().enumerate() {
            let Cell::Metres(z) = &row.cells[1] else {
                unreachable!()
            };
            for y in 0..h {
                for x in 0..w {
                    let hit = at(&drawn, 0, r, x, y) != [0, 0, 255];
                    assert_eq!(at(&drawn, 2, r, x, y), [if hit { 255 } else { 0 }; 3]);
                    for label in [3, 4] {
                        assert_eq!(at(&drawn, label, r, x, y) != [0; 3], hit, "{label} {r}");
                    }
                    let z = z[(y * w + x) as usize];
                    let colour = at(&drawn, 1, r, x, y);
                    if !hit {
                        background += 1;
                        assert_eq!(colour, [0; 3]);
                        continue;
                    }
                    surface += 1;
                    // The bar's place of this colour, read as metres from its end labels.
                    let i = (0..bar.len())
                        .min_by_key(|&i| distance(bar[i], colour))
                        .unwrap();
                    let read = near + (far - near) * i as f32 / (bar.len() - 1) as f32;
                    assert!(
                        (read - z).abs() <= 0.02 * (far - near),
                        "{z} m read as {read} m"
                    );
                }
            }
        }
        assert!(surface > 100 && background > 100, "{surface} {background}");
        // The bar's end labels are the sheet's nearest and farthest depth.
        let legend_area = (bx, by, legend::WIDTH, legend::HEIGHT);
        for value in [near, far] {
            let label = legend::tick(f64::from(value), f64::from(far - near));
            assert!(
                find_text(&drawn.canvas, legend_area, &label, 2),
                "no tick {label}"
            );
        }
    }

    #[test]
    fn normals_flow_and_displacement_get_columns_and_legends() {
        let outputs = r#"["rgb", "normals", "flow", "displacement"]"#;
        let drawn = sheet(BEAM, outputs, "", 64);
        assert_eq!(
            drawn.layers,
            [Layer::Rgb, Layer::Normals, Layer::Flow, Layer::Displacement]
        );
        let (w, h) = drawn.layout.cell;
        let mut largest_flow = 0.0_f32;
        for row in &drawn.rows {
            let Cell::Flow(flow) = &row.cells[2] else {
                unreachable!()
            };
            for (v, &ok) in flow.vectors.iter().zip(&flow.valid) {
                if ok != 0 {
                    largest_flow = largest_flow.max(v[0].hypot(v[1]));
                }
            }
        }
        assert!(largest_flow > 0.1, "the beam bends: {largest_flow}");
        for (r, row) in drawn.rows.iter().enumerate() {
            let Cell::Normals(normals) = &row.cells[1] else {
                unreachable!()
            };
            let Cell::Flow(flow) = &row.cells[2] else {
                unreachable!()
            };
            for y in 0..h {
                for x in 0..w {
                    let i = (y * w + x) as usize;
                    let n = normals[i];
                    let expected = if n == [0.0; 3] {
                        [0; 3]
                    } else {
                        n.map(|c| ((c + 1.0) / 2.0 * 255.0).round() as u8)
                    };
                    assert_eq!(at(&drawn, 1, r, x, y), expected, "normal {n:?}");
                    let flow_pixel = at(&drawn, 2, r, x, y);
                    assert_eq!(
                        flow_pixel == [0; 3],
                        flow.valid[i] == 0,
                        "flow at ({x}, {y})"
                    );
                }
            }
        }
        // Three legends, the flow's naming its largest motion.
        let (x, y) = drawn.layout.legend_at(1);
        let rim = format!(
            "rim {} px",
            legend::tick(f64::from(largest_flow), f64::from(largest_flow))
        );
        let area = (x, y, legend::WIDTH, legend::HEIGHT);
        assert!(
            (1..=2).any(|s| find_text(&drawn.canvas, area, &rim, s)),
            "no {rim}"
        );
        let (x, y) = drawn.layout.legend_at(2);
        let area = (x, y, legend::WIDTH, legend::HEIGHT);
        assert!(
            find_text(&drawn.canvas, area, "displacement", 2)
                || find_text(&drawn.canvas, area, "displacement", 1)
        );
    }

    #[test]
    fn a_recipe_without_cracks_says_so_instead_of_a_black_column() {
        let drawn = sheet(BLOCKS, r#"["rgb", "cracks"]"#, "", 240);
        assert_eq!(drawn.layers, [Layer::Rgb, Layer::Cracks]);
        let (w, h) = drawn.layout.cell;
        for r in 0..drawn.rows.len() {
            let (x, y) = drawn.layout.cell_at(1, r as u32);
            let black = (0..h).flat_map(|y| (0..w).map(move |x| (x, y)));
            assert!(
                black
                    .clone()
                    .all(|(px, py)| at(&drawn, 1, r, px, py) != [0; 3]),
                "row {r}: black pixels in the cracks cell"
            );
            let said = (1..=2).any(|s| find_text(&drawn.canvas, (x, y, w, h), "cracks", s));
            assert!(said, "row {r} does not say there are no cracks");
        }
        // A layer not written has no column: no mask, no depth.
        assert!(!drawn.layers.contains(&Layer::Mask));
    }

    #[test]
    fn augmented_copies_are_marked_rows_after_their_view() {
        let augment = r#"augment: #{ copies: 2, operations: [#{ op: "warp", zoom: [1.2, 1.5], rotation: [0.3, 1.0], shift_x: 0.0, shift_y: 0.0, probability: 1.0 }] },"#;
        let drawn = sheet(BLOCKS, r#"["rgb", "mask"]"#, augment, 32);
        if let Ok(p) = std::env::var("SHEET_DUMP") {
            let c = &drawn.canvas;
            std::fs::write(p, rgb_png(c.width(), c.height(), c.pixels())).unwrap();
        }
        let order: Vec<(u64, u32, Option<u32>)> = drawn
            .rows
            .iter()
            .map(|r| (r.sample, r.view, r.copy))
            .collect();
        let mut expected = Vec::new();
        for sample in 0..2 {
            for view in 0..2 {
                expected.extend([None, Some(0), Some(1)].map(|c| (sample, view, c)));
            }
        }
        assert_eq!(order, expected);
        let layout = &drawn.layout;
        for (r, row) in drawn.rows.iter().enumerate() {
            let area = label_area(layout, r);
            let marked = (1..=2).any(|s| find_text(&drawn.canvas, area, "copy", s));
            assert_eq!(marked, row.copy.is_some(), "row {r}");
            if let Some(copy) = row.copy {
                let text = format!("copy {} of 2", copy + 1);
                assert!(
                    (1..=2).any(|s| find_text(&drawn.canvas, area, &text, s)),
                    "{text}"
                );
            }
        }
        // The copies differ from their clean view (turned and zoomed).
        let rgb = |r: usize| match &drawn.rows[r].cells[0] {
            Cell::Colour(c) => c.clone(),
            _ => unreachable!(),
        };
        for view in 0..4 {
            let clean = rgb(3 * view);
            assert!(
                rgb(3 * view + 1) != clean && rgb(3 * view + 2) != clean,
                "{view}"
            );
        }
    }

    #[test]
    fn the_same_recipe_gives_the_same_sheet_bytes() {
        let outputs = r#"["rgb", "depth", "parts", "normals", "flow", "displacement"]"#;
        let a = sheet(BEAM, outputs, "", 48);
        let b = sheet(BEAM, outputs, "", 48);
        assert!(a.canvas.pixels() == b.canvas.pixels());
    }
}
