//! Iterating on a recipe: `shmgen watch` (hot reload into a contact sheet, optionally served
//! as a local web page) and `shmgen check` (validation and estimates of the full run).
//!
//! Owns: the preview sheet, file watching, the loopback web page and the check report. Must
//! not touch: how scenes are drawn, meshed, traced or encoded (it calls `pipeline::prepare`,
//! `SampleRenderer`, `pipeline::run` and the `output` encoders), the dataset format, or the
//! recipe's files (it only reads them). A preview is a picture for a person, never part of a
//! dataset.

mod canvas;
mod check;
mod colours;
mod legend;
mod serve;
mod sheet;
mod watch;

pub use check::check;
pub use sheet::{PreviewOptions, SEPARATOR, Size};
pub use watch::{WatchOptions, watch};
