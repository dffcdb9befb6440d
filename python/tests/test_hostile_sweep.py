"""Every kind of file of a dataset, made hostile in every way, given to the loader: the
Python side of ``tests/hostile_datasets.rs``. Each case starts from a copy of the box dataset
(every output, conftest), harms one file — truncated, emptied, scrambled, grown by 17 MiB, its
PNG header inflated to 40000 × 40000, replaced by a link outside the dataset, a link to
``/dev/zero``, a FIFO or a folder — with the manifest's hashes kept (the harm must be
noticed) or removed (as in a dataset from an older shmgen, so the decoders meet the bytes),
then opens the dataset and reads every layer, record, camera and mesh.

The loader must end within its deadline and either read the data or raise one of its
documented errors (``DatasetError``/``ValueError``, ``FileNotFoundError``, ``KeyError``) naming
the harmed file; never another exception, and never a byte of the file outside."""

from __future__ import annotations

import json
import os
import shutil
import struct
import zlib
from pathlib import Path

import pytest

from shmgen_data import Dataset

from test_untrusted import deadline

SECRET = b"SECRET-of-the-person-loading-7d21"
HARMS = ["truncated", "emptied", "scrambled", "grown", "inflated", "link_outside", "link_zero",
         "fifo", "folder"]
ENTRY_HARMS = {"link_outside", "link_zero", "fifo", "folder"}


def targets(box: Path) -> list[str]:
    """run.json, the manifest, and one file of each kind: view 0's and the sample's own."""
    first = json.loads((box / "manifest.jsonl").read_text().splitlines()[0])
    kinds = [f for f in first["files"] if "_00." in f or "_" not in f.rsplit("/", 1)[-1]]
    return ["run.json", "manifest.jsonl", *kinds]


def inflate_png(data: bytes) -> bytes | None:
    if len(data) < 33 or data[12:16] != b"IHDR":
        return None
    header = data[12:16] + struct.pack(">II", 40000, 40000) + data[24:29]
    return data[:12] + header + struct.pack(">I", zlib.crc32(header)) + data[33:]


def harm(root: Path, relative: str, how: str, secret: Path) -> bool:
    """Harms ``relative`` in the copy at ``root``; False if ``how`` does not apply to it."""
    path = root / relative
    data = path.read_bytes()
    if how == "truncated":
        data = data[: len(data) // 2]
    elif how == "emptied":
        data = b""
    elif how == "scrambled":
        data = bytearray(data)
        for i in range(len(data) // 3, len(data), 7):
            data[i] = (data[i] * 31 + 17) % 256
        data = bytes(data)
    elif how == "grown":
        data += b"A" * (17 << 20)
    elif how == "inflated":
        data = inflate_png(data)
        if data is None:
            return False
    path.unlink()
    if how == "link_outside":
        path.symlink_to(secret)
    elif how == "link_zero":
        path.symlink_to("/dev/zero")
    elif how == "fifo":
        os.mkfifo(path)
    elif how == "folder":
        path.mkdir()
    else:
        path.write_bytes(data)
    return True


def read_everything(root: Path) -> list:
    """Everything the loader offers, read: what a training script might touch."""
    data = Dataset(root)
    out = []
    for view in data:
        out.append(view.record)
        out.append(view.camera)
        for layer in view.layers:
            out.append(view.load(layer))
    for sample in data.samples:
        for kind in ("mesh", "rest_mesh", "points"):
            try:
                out.append(getattr(sample, kind)())
            except FileNotFoundError:
                pass  # the sample has no such file: not what is tested here
    return out


def contains_secret(values) -> bool:
    for value in values:
        try:
            raw = value.tobytes() if hasattr(value, "tobytes") else json.dumps(value, default=str).encode()
        except TypeError:
            continue
        if SECRET in raw:
            return True
    return False


@pytest.mark.parametrize("hashes", [True, False], ids=["hashes", "no-hashes"])
def test_every_hostile_file_is_read_right_or_refused_naming_it(box, tmp_path, hashes):
    secret = tmp_path / "secret.txt"
    secret.write_bytes(SECRET)
    failures, cases = [], 0
    for relative in targets(box):
        for how in HARMS:
            copy = tmp_path / "copy"
            shutil.rmtree(copy, ignore_errors=True)
            shutil.copytree(box, copy)
            if not hashes:
                lines = [json.loads(line) for line in (copy / "manifest.jsonl").read_text().splitlines()]
                for line in lines:
                    line.pop("hashes", None)
                (copy / "manifest.jsonl").write_text("".join(json.dumps(line) + "\n" for line in lines))
            if not harm(copy, relative, how, secret):
                continue
            cases += 1
            name = relative.rsplit("/", 1)[-1]
            try:
                with deadline(30):
                    values = read_everything(copy)
            except (ValueError, FileNotFoundError, KeyError) as error:
                if name not in str(error) and str(copy) not in str(error):
                    failures.append(f"{relative} {how}: the error does not name the file: {error}")
                continue
            except Exception as error:  # noqa: BLE001 - any other exception is the failure
                failures.append(f"{relative} {how}: {type(error).__name__}: {error}")
                continue
            # The hashes cover the samples' files; a torn tail of the manifest (what a killed
            # run leaves) is ignored by design.
            resized = how in {"truncated", "emptied", "grown"} and relative.startswith("samples/")
            if how in ENTRY_HARMS or (hashes and resized):
                failures.append(f"{relative} {how}: read without a word")
            if contains_secret(values):
                failures.append(f"{relative} {how}: a file from outside the dataset was read")
    assert cases > 100
    assert not failures, "\n".join(failures)
