//! `--format webdataset`: gzip-compressed tar shards `shard-{k:06}.tar.gz` (WebDataset opens
//! them as it opens plain tar), one WebDataset key per view (clean or
//! augmented copy): the file-name stem, e.g. `000003_01` or `000003_01a0`, which has no dot
//! (WebDataset splits a member's name at its first dot). Per-sample files (meshes) are not
//! views and stay out of the shards.
//!
//! Members are chosen so that WebDataset's own decoders (`.decode("rgb")`, `.decode("torch")`)
//! give training arrays, with no decoder of ours: a PNG decoded by them is always colour
//! (a mask would come out as three float channels) and EXR is not decoded at all. So:
//! - `rgb.png`, `rest_rgb.png` and `json` are the dataset's files, byte for byte;
//! - every EXR layer becomes `{layer}.npy`, float32, `(H, W)` for one channel (depth, rest
//!   depth, ray distance) or `(H, W, C)` in the record's channel order (normals, displacement
//!   x, y, z; flow u, v), which NumPy's `.npy` decoder in WebDataset reads as is;
//! - masks (`mask`, `cracks`, `erased`, `valid`, the flows' `…_valid`) become `{layer}.npy` bool
//!   `(H, W)`, and the id images (`parts`, `instances`) `{layer}.npy` int32 `(H, W)`.
//!
//! Shards: `--shard-size N` puts N views in each (the last holds the rest); by default the views
//! are split into near-equal shards, at least `MIN_SHARDS` of them (one per view when there are
//! fewer views) and as many more as keep them to `MAX_AUTO_VIEWS` views each. A DataLoader
//! worker reads whole shards, so a small export in a single shard leaves every worker but one
//! without data (WebDataset then stops with "No samples found").
//!
//! Shards are byte-for-byte deterministic: views in sample, view, copy order; POSIX ustar
//! headers with mode 0644, uid and gid 0, empty owner names and mtime 0; gzip at its fastest
//! level, with mtime 0 and no name. Uncompressed, float32 depth and int32 ids are 3.7 MB per
//! 960² view each, mostly background: gzip makes a quickstart export about as small as the
//! dataset's own PNG and EXR files.

use super::Job;
use crate::dataset::{Dataset, Hashing, View};
use crate::output::npy;
use anyhow::{Context, Result, bail};
use flate2::write::GzEncoder;
use flate2::{Compression, GzBuilder};
use rayon::prelude::*;
use serde_json::{Value, json};
use std::fs::File;
use std::io::{BufWriter, Read, Write};
use std::ops::Range;
use std::path::Path;

/// The fewest shards a default export is split into (fewer only if it has fewer views):
/// enough for `num_workers` up to 16, or 2 workers on each of 8 GPUs.
const MIN_SHARDS: usize = 16;

/// The most views a default shard holds, once a dataset is large enough to need more than
/// `MIN_SHARDS` shards (about 1–4 GB at 960 × 960 with depth and masks).
const MAX_AUTO_VIEWS: usize = 1000;

/// The masks, stored as PNGs of 0 and 255, written as bool arrays.
const MASKS: [&str; 7] = [
    "mask.png",
    "cracks.png",
    "erased.png",
    "valid.png",
    "flow_valid.png",
    "flow_next_valid.png",
    "flow_prev_valid.png",
];

/// The id images (8- or 16-bit PNGs), written as int32 arrays.
const IDS: [&str; 2] = ["parts.png", "instances.png"];

pub(super) fn write(job: &mut Job) -> Result<Value> {
    let (dataset, out, options) = (job.dataset, job.out, job.options);
    let views: Vec<&View> = dataset.views().collect();
    // Shards are independent: written in parallel, listed in order.
    let shards: Vec<Value> = shard_ranges(views.len(), options.shard_size)
        .into_par_iter()
        .enumerate()
        .map(|(k, range)| {
            let chunk = &views[range];
            let name = format!("shard-{k:06}.tar.gz");
            write_shard(dataset, &out.join(&name), chunk)
                .with_context(|| format!("writing {name}"))?;
            Ok(json!({
                "file": name,
                "views": chunk.len(),
                "first": chunk[0].stem,
                "last": chunk[chunk.len() - 1].stem,
            }))
        })
        .collect::<Result<_>>()?;
    job.placer.written += shards.len();
    job.summary.views += views.len();
    Ok(json!({
        "layout": "shard-{k:06}.tar.gz (gzip over tar); key {sample:06}_{view:02}[a{copy}]; members key.rgb.png, key.rest_rgb.png and key.json as in the dataset, key.{layer}.npy for the others: EXR layers float32 (H, W) or (H, W, C), masks bool (H, W), parts and instances int32 (H, W)",
        "shard_size": options.shard_size,
        "shards": shards,
    }))
}

/// The views of each shard: `size` views each if given, else near-equal shards as the module
/// says.
fn shard_ranges(views: usize, size: Option<usize>) -> Vec<Range<usize>> {
    let shards = match size {
        Some(size) => views.div_ceil(size),
        None => views.min(MIN_SHARDS.max(views.div_ceil(MAX_AUTO_VIEWS))),
    };
    let end = |k: usize| match size {
        Some(size) => (k * size).min(views),
        None => k * views / shards,
    };
    (0..shards).map(|k| end(k)..end(k + 1)).collect()
}

/// A shard being written: tar members, gzip-compressed, into a buffered file.
type Shard = tar::Builder<GzEncoder<BufWriter<File>>>;

fn write_shard(dataset: &Dataset, path: &Path, views: &[&View]) -> Result<()> {
    let file = File::create(path)?;
    // GzBuilder writes mtime 0 and no file name: the bytes depend on the contents only.
    let gzip = GzBuilder::new().write(BufWriter::new(file), Compression::fast());
    let mut tar = tar::Builder::new(gzip);
    for view in views {
        let record = dataset.record(view)?;
        for (kind, relative) in view.kinds() {
            let layer = kind.split('.').next().unwrap_or(kind);
            let name = format!("{}.{layer}.npy", view.stem);
            if kind.ends_with(".exr") {
                let channels = exr_channels(&record, layer, relative)?;
                let names: Vec<&str> = channels.iter().map(String::as_str).collect();
                append(&mut tar, &name, &float_npy(dataset, view, kind, &names)?)?;
            } else if MASKS.contains(&kind) {
                append(&mut tar, &name, &mask_npy(dataset, view, kind)?)?;
            } else if IDS.contains(&kind) {
                append(&mut tar, &name, &ids_npy(dataset, view, kind)?)?;
            } else {
                append_file(dataset, &mut tar, relative)?;
            }
        }
    }
    let mut writer = tar.into_inner()?.finish()?;
    writer.flush()?;
    Ok(())
}

/// The EXR channels of `layer` as the view's record names them (`depth.channel`,
/// `normals.channels`, …; `rest_depth` follows `depth`).
fn exr_channels(record: &Value, layer: &str, relative: &str) -> Result<Vec<String>> {
    let convention = match layer {
        // The damage layers share one convention.
        "crack_width" | "crack_coverage" => &record["damage"],
        // So do the flows between frames.
        "flow_next" | "flow_prev" => &record["frame_flow"],
        _ => &record[layer.strip_prefix("rest_").unwrap_or(layer)],
    };
    let names: Option<Vec<String>> = match (&convention["channels"], &convention["channel"]) {
        (Value::Array(list), _) => list
            .iter()
            .map(|c| c.as_str().map(str::to_string))
            .collect(),
        (_, Value::String(one)) => Some(vec![one.clone()]),
        _ => None,
    };
    names
        .filter(|n| !n.is_empty())
        .with_context(|| format!("{relative}: the view's record names no channels for {layer:?}"))
}

/// The float channels `names` of the view's EXR `kind`, as `(H, W)` or `(H, W, C)` float32,
/// refusing a value that is not finite (a dataset may be old, unhashed, or hand-edited).
fn float_npy(dataset: &Dataset, view: &View, kind: &str, names: &[&str]) -> Result<Vec<u8>> {
    let layer = dataset.layer(view, kind, &[names])?;
    let pixels = layer.width * layer.height;
    let mut data = Vec::with_capacity(pixels * names.len() * 4);
    for i in 0..pixels {
        for (plane, channel) in layer.channels.iter().zip(names) {
            let value = plane[i];
            if !value.is_finite() {
                bail!(
                    "view {} {kind}: channel {channel} at (row {}, column {}) is {value}; values must be finite",
                    view.stem,
                    i / layer.width,
                    i % layer.width
                );
            }
            data.extend_from_slice(&value.to_le_bytes());
        }
    }
    let mut shape = vec![layer.height, layer.width];
    if names.len() > 1 {
        shape.push(names.len());
    }
    Ok(npy("<f4", &shape, &data))
}

/// The view's mask `kind` as `(H, W)` bool, refusing values other than 0 and 255.
fn mask_npy(dataset: &Dataset, view: &View, kind: &str) -> Result<Vec<u8>> {
    let image = dataset.grey(view, kind)?;
    let mut data = Vec::with_capacity(image.values.len());
    for (i, &value) in image.values.iter().enumerate() {
        if image.bits != 8 || (value != 0 && value != 255) {
            bail!(
                "view {} {kind}: (row {}, column {}) holds {value} in a {}-bit PNG; a mask is 8-bit, 0 or 255",
                view.stem,
                i / image.width,
                i % image.width,
                image.bits
            );
        }
        data.push(u8::from(value == 255));
    }
    Ok(npy("|b1", &[image.height, image.width], &data))
}

/// The view's id image `kind` as `(H, W)` int32.
fn ids_npy(dataset: &Dataset, view: &View, kind: &str) -> Result<Vec<u8>> {
    let image = dataset.grey(view, kind)?;
    let data: Vec<u8> = image
        .values
        .iter()
        .flat_map(|&id| i32::from(id).to_le_bytes())
        .collect();
    Ok(npy("<i4", &[image.height, image.width], &data))
}

/// A ustar header for a member of `size` bytes, with nothing of the machine in it.
fn header(size: u64) -> Result<tar::Header> {
    let mut header = tar::Header::new_ustar();
    header.set_entry_type(tar::EntryType::Regular);
    header.set_size(size);
    header.set_mode(0o644);
    header.set_uid(0);
    header.set_gid(0);
    header.set_mtime(0);
    header.set_username("")?;
    header.set_groupname("")?;
    Ok(header)
}

/// Appends `bytes` as the member `name`.
fn append(tar: &mut Shard, name: &str, bytes: &[u8]) -> Result<()> {
    // append_data sets the name and the checksum.
    tar.append_data(&mut header(bytes.len() as u64)?, name, bytes)
        .with_context(|| format!("adding {name}"))
}

/// Appends the dataset's file `relative` under its own name, as it is.
fn append_file(dataset: &Dataset, tar: &mut Shard, relative: &str) -> Result<()> {
    // Opened as an untrusted dataset's files are; packed as far as the size it had when
    // opened, and checked against the manifest's hash as it is packed.
    let (data, check) = dataset.open_file(relative)?;
    let size = data.metadata()?.len();
    let mut data = Hashing::new(data.take(size));
    let name = relative.rsplit('/').next().unwrap_or(relative);
    tar.append_data(&mut header(size)?, name, &mut data)
        .with_context(|| format!("adding {relative}"))?;
    if let Some(check) = check {
        check.hash(data.hash(), relative)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sizes(ranges: &[Range<usize>]) -> Vec<usize> {
        ranges.iter().map(ExactSizeIterator::len).collect()
    }

    fn assert_covers(ranges: &[Range<usize>], views: usize) {
        let mut next = 0;
        for range in ranges {
            assert_eq!(range.start, next, "contiguous");
            assert!(range.end > range.start, "no empty shard");
            next = range.end;
        }
        assert_eq!(next, views, "every view once");
    }

    #[test]
    fn a_given_shard_size_fills_each_shard_but_the_last() {
        let ranges = shard_ranges(6, Some(4));
        assert_eq!(sizes(&ranges), [4, 2]);
        assert_covers(&ranges, 6);
        assert_eq!(sizes(&shard_ranges(8, Some(4))), [4, 4]);
    }

    #[test]
    fn the_default_gives_every_worker_a_shard() {
        // The quickstart's 24 views: 16 shards of 1 or 2 views, not one shard of 24.
        let ranges = shard_ranges(24, None);
        assert_eq!(ranges.len(), MIN_SHARDS);
        assert_covers(&ranges, 24);
        assert!(sizes(&ranges).iter().all(|&n| n == 1 || n == 2));
        // Fewer views than MIN_SHARDS: one each.
        assert_eq!(sizes(&shard_ranges(3, None)), [1, 1, 1]);
        // Large: at most MAX_AUTO_VIEWS each, near-equal.
        let ranges = shard_ranges(100_001, None);
        assert_covers(&ranges, 100_001);
        assert_eq!(ranges.len(), 101);
        assert!(sizes(&ranges).iter().all(|&n| n == 990 || n == 991));
        assert!(shard_ranges(0, None).is_empty());
    }
}
