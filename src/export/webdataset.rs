//! `--format webdataset`: tar shards `shard-{k:06}.tar` of `--shard-size` views each, one
//! WebDataset key per view (clean or augmented copy): the file-name stem, e.g. `000003_01` or
//! `000003_01a0`, which has no dot (WebDataset splits a member's name at its first dot). Each
//! key's members are the view's files under their own names (`000003_01.depth.exr`,
//! `000003_01.json`, `000003_01.rgb.png`, …), adjacent and sorted, as WebDataset needs.
//! Per-sample files (meshes) are not views and stay out of the shards.
//!
//! Shards are byte-for-byte deterministic: views in sample, view, copy order; POSIX ustar
//! headers with mode 0644, uid and gid 0, empty owner names and mtime 0.

use super::Job;
use crate::dataset::{Dataset, Hashing, View};
use anyhow::{Context, Result};
use serde_json::{Value, json};
use std::fs::File;
use std::io::{BufWriter, Read, Write};
use std::path::Path;

pub(super) fn write(job: &mut Job) -> Result<Value> {
    let (dataset, out, options) = (job.dataset, job.out, job.options);
    let views: Vec<&View> = dataset.views().collect();
    let mut shards = Vec::new();
    for (k, chunk) in views.chunks(options.shard_size).enumerate() {
        let name = format!("shard-{k:06}.tar");
        let path = out.join(&name);
        write_shard(dataset, &path, chunk).with_context(|| format!("writing {name}"))?;
        job.placer.written += 1;
        job.summary.views += chunk.len();
        shards.push(json!({
            "file": name,
            "views": chunk.len(),
            "first": chunk[0].stem,
            "last": chunk[chunk.len() - 1].stem,
        }));
    }
    Ok(json!({
        "layout": "shard-{k:06}.tar; key {sample:06}_{view:02}[a{copy}], members key.{kind} (rgb.png, depth.exr, mask.png, json, …)",
        "shard_size": options.shard_size,
        "shards": shards,
    }))
}

fn write_shard(dataset: &Dataset, path: &Path, views: &[&View]) -> Result<()> {
    let file = File::create(path)?;
    let mut tar = tar::Builder::new(BufWriter::new(file));
    for view in views {
        for relative in &view.files {
            // Opened as an untrusted dataset's files are; packed as far as the size it had
            // when opened, and checked against the manifest's hash as it is packed.
            let (data, check) = dataset.open_file(relative)?;
            let size = data.metadata()?.len();
            let mut data = Hashing::new(data.take(size));
            let name = relative.rsplit('/').next().unwrap_or(relative);
            let mut header = tar::Header::new_ustar();
            header.set_entry_type(tar::EntryType::Regular);
            header.set_size(size);
            header.set_mode(0o644);
            header.set_uid(0);
            header.set_gid(0);
            header.set_mtime(0);
            header.set_username("")?;
            header.set_groupname("")?;
            // append_data sets the name and the checksum.
            tar.append_data(&mut header, name, &mut data)
                .with_context(|| format!("adding {relative}"))?;
            if let Some(check) = check {
                check.hash(data.hash(), relative)?;
            }
        }
    }
    let mut writer = tar.into_inner()?;
    writer.flush()?;
    Ok(())
}
