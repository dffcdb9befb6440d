//! The contact sheet's legends: a colour bar with tick labels for a scalar (metres of depth,
//! displacement magnitude), the (n + 1) / 2 disc of normals, the flow colour wheel with its
//! largest motion, and the names of labels beside their colours.
//!
//! Owns: what a legend box shows and where inside the box. Draws with the same colour
//! functions as the cells (`colours`), so a legend cannot disagree with its column.

use super::canvas::{Canvas, Rgb, clipped, fitting_scale, text_width};
use super::colours::{flow_colour, id_colour, normal_colour, ramp};
use crate::scene::NormalsFrame;

/// Size of one legend box, pixels.
pub const WIDTH: u32 = 300;
pub const HEIGHT: u32 = 104;
const PAD: u32 = 6;
const FILL: Rgb = [56, 56, 56];
const INK: Rgb = [235, 235, 235];
/// Where the colour bar lies inside its box: left edge, top, width and height.
pub const BAR_LEFT: u32 = 24;
pub const BAR_TOP: u32 = 28;
pub const BAR_WIDTH: u32 = WIDTH - 2 * BAR_LEFT;
const BAR_HEIGHT: u32 = 22;
/// Radius of the normals and flow discs.
const DISC: u32 = 36;

/// What one legend box explains.
#[derive(Clone, Debug, PartialEq)]
pub enum Legend {
    /// A scalar ramp from `low` (left) to `high` (right) in `unit`. `near_is_red`: the ramp
    /// runs red → blue along the bar (depth: near is red), else blue → red.
    Bar {
        title: String,
        low: f64,
        high: f64,
        near_is_red: bool,
        note: String,
    },
    /// Normals as (n + 1) / 2 in the dataset's axes.
    Normals(NormalsFrame),
    /// The flow wheel; `max` pixels of motion reach its rim.
    Flow { max: f32 },
    /// Label names, each in `id_colour(index + 1)`.
    Names {
        title: &'static str,
        names: Vec<String>,
    },
}

/// Colour of the bar at `t` in [0, 1] from its left end; the cells use the same mapping.
pub fn bar_colour(t: f64, near_is_red: bool) -> Rgb {
    ramp(if near_is_red { 1.0 - t } else { t })
}

/// Draws `legend` in the box whose top-left corner is (x, y).
pub fn draw(canvas: &mut Canvas, x: u32, y: u32, legend: &Legend) {
    canvas.fill(x, y, WIDTH, HEIGHT, FILL);
    let title = match legend {
        Legend::Bar { title, .. } => title.as_str(),
        Legend::Normals(_) => "normals: RGB = (n+1)/2",
        Legend::Flow { .. } => "flow (Middlebury wheel)",
        Legend::Names { title, .. } => title,
    };
    line(canvas, x + PAD, y + PAD, title, WIDTH - 2 * PAD, 2);
    match legend {
        Legend::Bar {
            low,
            high,
            near_is_red,
            note,
            ..
        } => bar(canvas, x, y, (*low, *high), *near_is_red, note),
        Legend::Normals(frame) => normals(canvas, x, y, *frame),
        Legend::Flow { max } => flow(canvas, x, y, *max),
        Legend::Names { names, .. } => name_list(canvas, x, y, names),
    }
}

/// Text at (x, y), at most `largest` times the font's size and at least once, cut to `width`.
fn line(canvas: &mut Canvas, x: u32, y: u32, text: &str, width: u32, largest: u32) {
    let scale = fitting_scale(text, width, largest);
    canvas.text(x, y, &clipped(text, width, scale), scale, INK);
}

fn bar(canvas: &mut Canvas, x: u32, y: u32, (low, high): (f64, f64), red: bool, note: &str) {
    let denominator = f64::from(BAR_WIDTH - 1);
    for i in 0..BAR_WIDTH {
        let colour = bar_colour(f64::from(i) / denominator, red);
        canvas.fill(x + BAR_LEFT + i, y + BAR_TOP, 1, BAR_HEIGHT, colour);
    }
    let span = high - low;
    for (i, t) in [0.0, 0.5, 1.0].into_iter().enumerate() {
        let at = x + BAR_LEFT + (t * denominator).round() as u32;
        let tick_top = y + BAR_TOP + BAR_HEIGHT;
        canvas.fill(at, tick_top, 1, 5, INK);
        let label = tick(low + t * span, span);
        let width = text_width(&label, 2);
        // Centred on the tick, except the ends, which align with the bar's ends.
        let left = match i {
            0 => at.saturating_sub(width / 2).max(x + PAD),
            1 => at.saturating_sub(width / 2),
            _ => (at + width / 2).min(x + WIDTH - PAD) - width,
        };
        canvas.text(left, tick_top + 7, &label, 2, INK);
    }
    line(canvas, x + PAD, y + HEIGHT - 12, note, WIDTH - 2 * PAD, 1);
}

/// A tick value with as many decimals as the bar's span needs (three significant digits of
/// the span), never "-0".
pub fn tick(value: f64, span: f64) -> String {
    let decimals = if span > 0.0 {
        (2 - span.log10().floor() as i32).clamp(0, 4) as usize
    } else {
        2
    };
    let text = format!("{value:.decimals$}");
    match text.strip_prefix('-') {
        Some(rest) if rest.chars().all(|c| c == '0' || c == '.') => rest.to_string(),
        _ => text,
    }
}

/// Calls `paint` with each pixel of a disc of radius `DISC` at the left of a box and its
/// offset from the centre as a fraction of the radius.
fn disc(canvas: &mut Canvas, x: u32, y: u32, paint: impl Fn(f64, f64) -> Rgb) {
    let (cx, cy) = (x + PAD + DISC, y + HEIGHT - PAD - DISC - 1);
    let r = f64::from(DISC);
    for dy in -(DISC as i64)..=DISC as i64 {
        for dx in -(DISC as i64)..=DISC as i64 {
            let (fx, fy) = (dx as f64 / r, dy as f64 / r);
            if fx * fx + fy * fy <= 1.0 {
                canvas.set(i64::from(cx) + dx, i64::from(cy) + dy, paint(fx, fy));
            }
        }
    }
}

/// Lines of small text to the right of a disc.
fn beside_disc(canvas: &mut Canvas, x: u32, y: u32, lines: &[&str]) {
    let left = x + 2 * PAD + 2 * DISC + 4;
    for (i, text) in lines.iter().enumerate() {
        line(
            canvas,
            left,
            y + 32 + 16 * i as u32,
            text,
            x + WIDTH - PAD - left,
            2,
        );
    }
}

fn normals(canvas: &mut Canvas, x: u32, y: u32, frame: NormalsFrame) {
    match frame {
        // The normals a camera sees face it: z < 0 in OpenCV axes, x right and y down.
        NormalsFrame::Camera => {
            disc(canvas, x, y, |u, v| {
                let z = -(1.0 - u * u - v * v).max(0.0).sqrt();
                normal_colour([u as f32, v as f32, z as f32])
            });
            beside_disc(
                canvas,
                x,
                y,
                &["camera axes", "x right y down", "z forward"],
            );
        }
        // Seen from above: east (x) right, north (y) up, normals pointing up.
        NormalsFrame::World => {
            disc(canvas, x, y, |u, v| {
                let z = (1.0 - u * u - v * v).max(0.0).sqrt();
                normal_colour([u as f32, -v as f32, z as f32])
            });
            beside_disc(
                canvas,
                x,
                y,
                &["world axes", "seen from +z", "x right y up"],
            );
        }
    }
}

fn flow(canvas: &mut Canvas, x: u32, y: u32, max: f32) {
    disc(canvas, x, y, |u, v| {
        flow_colour(u as f32 * max, v as f32 * max, max)
    });
    let rim = format!("rim {} px", tick(f64::from(max), f64::from(max)));
    beside_disc(canvas, x, y, &[&rim, "u right v down", "black: no flow"]);
}

/// Swatch and name of each label, in two columns; "+N more" when they do not all fit.
fn name_list(canvas: &mut Canvas, x: u32, y: u32, names: &[String]) {
    const ROW: u32 = 12;
    let per_column = (HEIGHT - 28) / ROW;
    let capacity = (2 * per_column) as usize;
    let shown = if names.len() > capacity {
        capacity - 1
    } else {
        names.len()
    };
    let column_width = (WIDTH - 2 * PAD) / 2;
    for (i, name) in names.iter().take(shown).enumerate() {
        let (column, row) = (i as u32 / per_column, i as u32 % per_column);
        let (left, top) = (x + PAD + column * column_width, y + 28 + row * ROW);
        canvas.fill(left, top, 10, 10, id_colour(i as u32 + 1));
        line(canvas, left + 14, top + 1, name, column_width - 16, 1);
    }
    if shown < names.len() {
        let i = shown as u32;
        let (left, top) = (
            x + PAD + (i / per_column) * column_width,
            y + 28 + (i % per_column) * ROW,
        );
        let more = format!("+{} more", names.len() - shown);
        line(canvas, left + 14, top + 1, &more, column_width - 16, 1);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ticks_carry_the_decimals_the_span_needs() {
        assert_eq!(tick(2.346, 1.5), "2.35");
        assert_eq!(tick(12.0, 40.0), "12.0");
        assert_eq!(tick(0.0123, 0.02), "0.0123");
        assert_eq!(tick(350.0, 300.0), "350");
        assert_eq!(tick(-0.0001, 1.0), "0.00");
    }

    #[test]
    fn a_bar_runs_the_ramp_in_the_direction_it_says() {
        let mut canvas = Canvas::new(WIDTH, HEIGHT, [0; 3]);
        let legend = Legend::Bar {
            title: "depth, m".into(),
            low: 1.0,
            high: 3.0,
            near_is_red: true,
            note: String::new(),
        };
        draw(&mut canvas, 0, 0, &legend);
        let left = canvas.get(BAR_LEFT, BAR_TOP + 2);
        let right = canvas.get(BAR_LEFT + BAR_WIDTH - 1, BAR_TOP + 2);
        assert!(left[0] > 150 && left[2] < 60, "near end red: {left:?}");
        assert!(right[2] > right[0], "far end blue: {right:?}");
    }
}
