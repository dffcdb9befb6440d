"""A dataset handed to the loader is untrusted input: links are not followed below its root,
FIFOs and devices are refused without blocking, reads are bounded, image headers are checked
against the view before pixels are decoded, values that break the layout's rules (NaN or
negative depth, normals not unit, masks not 0/255, ids beyond their tables, mesh faces beyond
their vertices) are refused, and sizes and BLAKE3s are checked against the manifest's
``hashes``. Every refusal names the file. Each case starts from a copy of the box dataset
(conftest) and breaks one thing, as a corrupted download or a hostile sender would."""

from __future__ import annotations

import json
import os
import shutil
import signal
import struct
import zlib
from contextlib import contextmanager
from pathlib import Path

import blake3
import numpy as np
import OpenEXR
import pytest

from shmgen_data import Dataset, read_exr, read_ply, read_png
from shmgen_data import files as files_module

VIEW = "samples/0000/000000_00"  # the first clean view of the box dataset


@contextmanager
def deadline(seconds: int = 20):
    """Fails the test (instead of hanging) if the block runs longer than ``seconds``."""

    def expire(*_):
        raise TimeoutError(f"still running after {seconds} s: the loader blocked or read without bound")

    previous = signal.signal(signal.SIGALRM, expire)
    signal.alarm(seconds)
    try:
        yield
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, previous)


@pytest.fixture
def copy(box, tmp_path) -> Path:
    """A fresh copy of the box dataset, to break, without the manifest's ``hashes`` (as an
    older shmgen wrote it), so that each case meets the check it is about; the cases about
    hashes add them."""
    target = tmp_path / "box"
    shutil.copytree(box, target)
    entries = manifest_lines(target)
    for entry in entries:
        entry.pop("hashes", None)
    write_manifest(target, entries)
    return target


def manifest_lines(root: Path) -> list[dict]:
    return [json.loads(line) for line in (root / "manifest.jsonl").read_text().splitlines()]


def write_manifest(root: Path, entries: list[dict]) -> None:
    (root / "manifest.jsonl").write_text("".join(json.dumps(e) + "\n" for e in entries))


def add_hashes(root: Path) -> None:
    """Gives every manifest line the ``hashes`` shmgen writes (computed here with the blake3
    package; the same values as the binary's when it writes them itself)."""
    entries = manifest_lines(root)
    for entry in entries:
        entry["hashes"] = {
            relative: {"bytes": (root / relative).stat().st_size,
                       "blake3": blake3.blake3((root / relative).read_bytes()).hexdigest()}
            for relative in entry["files"]
        }
    write_manifest(root, entries)


def write_exr(path: Path, channels: dict) -> None:
    """An EXR as shmgen lays it out (float channels, scanlines, ZIP), written with the
    OpenEXR package."""
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    planes = {name: np.ascontiguousarray(plane, dtype=np.float32) for name, plane in channels.items()}
    OpenEXR.File(header, planes).write(str(path))


def write_depth(path: Path, depth: np.ndarray) -> None:
    write_exr(path, {"Y": depth})


def png_bytes(width: int, height: int, rows: bytes, colour_type: int = 2, depth: int = 8) -> bytes:
    """A PNG assembled chunk by chunk: an IHDR declaring ``width × height`` and ``rows`` as
    its (compressed) pixel data, whatever they hold."""

    def chunk(kind: bytes, data: bytes) -> bytes:
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))

    ihdr = struct.pack(">IIBBBBB", width, height, depth, colour_type, 0, 0, 0)
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IDAT", zlib.compress(rows))
            + chunk(b"IEND", b""))


# ---------------------------------------------------------------------------------------
# Links, FIFOs, devices


@pytest.fixture(params=["dir_fd", "lstat"])
def walker(request, monkeypatch):
    """Both ways of opening without links: by folder descriptors (POSIX) and the lstat walk
    used where ``dir_fd`` is not supported."""
    monkeypatch.setattr(files_module, "_DIR_FD", request.param == "dir_fd")
    return request.param


def test_a_file_linked_outside_the_dataset_is_refused(copy, tmp_path, walker):
    target = copy / f"{VIEW}.depth.exr"
    outside = tmp_path / "outside.exr"
    shutil.copy(target, outside)  # the same bytes: only the link is wrong
    target.unlink()
    target.symlink_to(outside)
    with pytest.raises(ValueError, match=f"000000_00.depth.exr: is a symbolic link"):
        Dataset(copy)
    # Linked after the dataset was opened: the read refuses it too.
    target.unlink()
    shutil.copy(outside, target)
    view = Dataset(copy)[0]
    target.unlink()
    target.symlink_to(outside)
    with pytest.raises(ValueError, match=f"000000_00.depth.exr: is a symbolic link"):
        view.depth


def test_a_linked_parent_folder_is_refused(copy, tmp_path, walker):
    folder = copy / "samples" / "0000"
    outside = tmp_path / "elsewhere"
    shutil.move(folder, outside)
    folder.symlink_to(outside, target_is_directory=True)
    with pytest.raises(ValueError, match=r"samples/0000: is a symbolic link"):
        Dataset(copy)
    folder.unlink()
    shutil.move(outside, folder)
    view = Dataset(copy)[0]
    shutil.move(folder, outside)
    folder.symlink_to(outside, target_is_directory=True)
    with pytest.raises(ValueError, match=r"samples/0000: is a symbolic link"):
        view.rgb


def test_the_root_itself_may_be_a_link(box, tmp_path):
    link = tmp_path / "link"
    link.symlink_to(box, target_is_directory=True)
    data = Dataset(link)
    assert data[0].depth.shape == (120, 160)
    assert len(data) == len(Dataset(box))


def test_a_file_linked_to_dev_zero_is_refused(copy, tmp_path):
    target = copy / f"{VIEW}.rgb.png"
    view = Dataset(copy)[0]
    target.unlink()
    target.symlink_to("/dev/zero")
    with deadline():
        with pytest.raises(ValueError, match="000000_00.rgb.png: is a symbolic link"):
            view.rgb
        with pytest.raises(ValueError, match="000000_00.rgb.png: is a symbolic link"):
            Dataset(copy)
        # Named by the user, the link is followed, and the device refused.
        with pytest.raises(ValueError, match="rgb.png: is a device"):
            read_png(target)
        with pytest.raises(ValueError, match="zero: is a device"):
            read_ply("/dev/zero")


def test_a_fifo_never_blocks(copy):
    target = copy / f"{VIEW}.json"
    view = Dataset(copy)[0]  # opened first: the FIFO appears between the listing and the read
    target.unlink()
    os.mkfifo(target)
    with deadline(10):
        with pytest.raises(ValueError, match="000000_00.json: is a FIFO"):
            view.record
        with pytest.raises(ValueError, match="000000_00.json: is a FIFO"):
            Dataset(copy)
        with pytest.raises(ValueError, match="000000_00.json: is a FIFO"):
            read_exr(target, ["Y"])


# ---------------------------------------------------------------------------------------
# Paths from the manifest


@pytest.mark.parametrize("bad", ["../outside.json", "/etc/hostname", "samples\\0000\\000000_00.json",
                                 "samples//0000/000000_00.json", "samples/./0000/000000_00.json"])
def test_manifest_paths_leaving_the_plain_layout_are_refused(copy, bad):
    (copy.parent / "outside.json").write_text("{}")
    entries = manifest_lines(copy)
    entries[0]["files"].append(bad)
    write_manifest(copy, entries)
    with pytest.raises(ValueError, match=r"manifest.jsonl: sample 0: .* not a plain relative path"):
        Dataset(copy)


# ---------------------------------------------------------------------------------------
# Headers before pixels, truncation, bounds


@pytest.mark.parametrize("layer", ["depth", "rgb", "normals", "parts"])
def test_a_truncated_image_is_refused(copy, layer):
    view = Dataset(copy)[0]
    path = view.path(layer)
    whole = path.read_bytes()
    for cut in (len(whole) - 12, len(whole) // 2, 40):
        path.write_bytes(whole[:cut])
        with pytest.raises(ValueError, match=path.name):
            Dataset(copy)[0].load(layer)


def test_exr_reads_without_stream_support(copy, monkeypatch):
    """OpenEXR before 3.5 reads files only: the bytes read go through a temporary copy."""
    expected = Dataset(copy)[0].depth
    streams = OpenEXR.File

    def files_only(source, *args, **kwargs):
        if not isinstance(source, str):
            raise TypeError("__init__(): incompatible constructor arguments")
        return streams(source, *args, **kwargs)

    monkeypatch.setattr(OpenEXR, "File", files_only)
    assert np.array_equal(Dataset(copy)[0].depth, expected)
    (copy / f"{VIEW}.depth.exr").write_bytes((copy / f"{VIEW}.depth.exr").read_bytes()[:-30])
    with pytest.raises(ValueError, match="000000_00.depth.exr: not a readable OpenEXR file"):
        Dataset(copy)[0].depth


def test_a_png_declaring_40000_by_40000_is_refused_before_decoding(copy, tmp_path):
    huge = png_bytes(40000, 40000, b"\0" * 1000)
    target = copy / f"{VIEW}.rgb.png"
    target.write_bytes(huge)
    with deadline(10):
        with pytest.raises(ValueError, match=r"000000_00.rgb.png: the header says 40000×40000 pixels, the camera has 160×120"):
            Dataset(copy)[0].rgb
        # Alone, without a camera to compare with: beyond Limits.max_side.
        with pytest.raises(ValueError, match=r"rgb.png: the header says 40000×40000 pixels; each side must be 1…16384"):
            read_png(target)
        # A record claiming that size too is refused before any image is read.
        record = copy / f"{VIEW}.json"
        values = json.loads(record.read_text())
        values["camera"]["width"] = values["camera"]["height"] = 40000
        record.write_text(json.dumps(values))
        with pytest.raises(ValueError, match=r"000000_00.json: camera 40000×40000 pixels"):
            Dataset(copy)[0].rgb


def test_an_image_of_the_wrong_format_or_size_is_refused(copy):
    target = copy / f"{VIEW}.mask.png"
    target.write_bytes(png_bytes(160, 120, b"\0" * (120 * (1 + 160 * 3)), colour_type=2))
    with pytest.raises(ValueError, match=r"000000_00.mask.png: a 8-bit RGB PNG; 8-bit grey is expected"):
        Dataset(copy)[0].mask
    depth = copy / f"{VIEW}.depth.exr"
    write_depth(depth, np.ones((60, 80)))
    with pytest.raises(ValueError, match=r"000000_00.depth.exr: the header says 80×60 pixels, the camera has 160×120"):
        Dataset(copy)[0].depth


def test_a_file_larger_than_its_bound_is_refused_before_it_is_read(copy):
    # A valid PNG followed by 2 MiB of padding: more than 2 × 160 × 120 × 3 + 1 MiB.
    target = copy / f"{VIEW}.rgb.png"
    target.write_bytes(target.read_bytes() + b"\0" * (2 << 20))
    with pytest.raises(ValueError, match=r"000000_00.rgb.png: \d+ bytes, more than the 1163776 allowed for a 160×120 image"):
        Dataset(copy)[0].rgb


def test_every_kind_has_its_bound(copy):
    from shmgen_data import Limits

    view_json = (copy / f"{VIEW}.json").stat().st_size
    with pytest.raises(ValueError, match=r"000000_00.json: \d+ bytes, more than the \d+ allowed for a JSON record \(Limits.record_bytes\)"):
        Dataset(copy, limits=Limits(record_bytes=max(100, (copy / "run.json").stat().st_size)))[0].record
    assert view_json > 100
    with pytest.raises(ValueError, match=r"manifest.jsonl: a line longer than the 1000 bytes allowed for a manifest line"):
        Dataset(copy, limits=Limits(manifest_line_bytes=1000))
    with pytest.raises(ValueError, match=r"manifest.jsonl: \d+ bytes, more than the 1000 allowed for manifest.jsonl"):
        Dataset(copy, limits=Limits(manifest_bytes=1000))
    with pytest.raises(ValueError, match=r"000000.points.ply: \d+ bytes, more than the 1000 allowed for a PLY file"):
        Dataset(copy, limits=Limits(mesh_bytes=1000)).samples[0].points()


def test_a_ply_declaring_more_records_than_it_holds_is_refused(copy):
    target = copy / "samples/0000/000000.points.ply"
    data = target.read_bytes()
    header_end = data.index(b"end_header\n")
    header = data[:header_end].replace(b"element vertex 100000", b"element vertex 100000000000000")
    target.write_bytes(header + data[header_end:])
    with deadline(10), pytest.raises(ValueError, match=r"points.ply: PLY element 'vertex' declares 100000000000000 records"):
        Dataset(copy).samples[0].points()


# ---------------------------------------------------------------------------------------
# Values the layout does not allow


@pytest.mark.parametrize("bad", [np.nan, -0.5, np.inf])
def test_nan_inf_or_negative_depth_is_refused_naming_the_pixel(copy, bad):
    path = copy / f"{VIEW}.depth.exr"
    depth = Dataset(copy)[0].depth.copy()
    depth[7, 11] = bad
    depth[50, 3] = bad
    write_depth(path, depth)
    with pytest.raises(ValueError, match=rf"000000_00.depth.exr: pixel \(row 7, column 11\) holds {bad}; "
                                         r"a distance must be finite and ≥ 0 \(0 = no surface\) \(2 such pixels\)"):
        Dataset(copy)[0].depth


def test_normals_masks_ids_and_flow_out_of_their_range_are_refused(copy):
    view = Dataset(copy)[0]
    normals = view.normals.copy()
    surface = np.argwhere(view.mask)[0]
    normals[tuple(surface)] *= 2.0
    write_exr(view.path("normals"), {c: normals[..., k] for k, c in enumerate("RGB")})
    with pytest.raises(ValueError, match=rf"normals.exr: pixel \(row {surface[0]}, column {surface[1]}\) .* length 1"):
        Dataset(copy)[0].normals
    flow = view.flow.copy()
    flow[3, 4, 1] = np.nan
    write_exr(view.path("flow"), {"R": flow[..., 0], "G": flow[..., 1]})
    with pytest.raises(ValueError, match=r"flow.exr: pixel \(row 3, column 4\) holds \[0.0, nan\]; values must be finite"):
        Dataset(copy)[0].flow
    grey = lambda value: png_bytes(160, 120, b"".join(b"\0" + bytes([value]) * 160 for _ in range(120)), 0)
    view.path("mask").write_bytes(grey(7))
    with pytest.raises(ValueError, match=r"mask.png: pixel \(row 0, column 0\) holds 7; a mask holds 0 and 255 only"):
        Dataset(copy)[0].mask
    parts = len(view.record["segmentation"]["part_ids"])
    view.path("parts").write_bytes(grey(parts))
    with pytest.raises(ValueError, match=rf"parts.png: pixel \(row 0, column 0\) holds {parts}; an id must index segmentation.part_ids"):
        Dataset(copy)[0].parts


def test_meshes_with_faces_beyond_their_vertices_or_nan_coordinates_are_refused(copy):
    sample = Dataset(copy).samples[0]
    path = sample.path("mesh.ply")
    data = bytearray(path.read_bytes())
    body = data.index(b"end_header\n") + len(b"end_header\n")
    vertices = sample.mesh().vertices
    # The first face's first index (after the vertices' doubles and its uchar count) → 10**6.
    first_index = body + vertices.size * 8 + 1
    good = bytes(data)
    data[first_index:first_index + 4] = struct.pack("<i", 10**6)
    path.write_bytes(bytes(data))
    with pytest.raises(ValueError, match=rf"mesh.ply: face 0 is \[1000000, .*vertex indices must be 0…{len(vertices) - 1}"):
        sample.mesh()
    data = bytearray(good)
    data[body:body + 8] = struct.pack("<d", np.nan)
    path.write_bytes(bytes(data))
    with pytest.raises(ValueError, match=r"mesh.ply: vertex 0 holds \[nan, .*coordinates must be finite"):
        sample.mesh()


# ---------------------------------------------------------------------------------------
# Hashes


def test_a_file_whose_size_differs_from_its_hash_is_refused(copy):
    add_hashes(copy)
    data = Dataset(copy)
    assert data[0].depth.shape == (120, 160)
    path = copy / f"{VIEW}.normals.exr"
    size = path.stat().st_size
    view = data[0]
    path.write_bytes(path.read_bytes()[:-1])
    message = rf"000000_00.normals.exr: {size - 1} bytes, the manifest's hashes say {size} \(truncated or altered\)"
    with pytest.raises(ValueError, match=message):
        view.normals
    with pytest.raises(ValueError, match=message):
        Dataset(copy)


def test_verify_reports_altered_and_truncated_files(copy):
    add_hashes(copy)
    listed = sum(len(set(entry["files"])) for entry in manifest_lines(copy))
    clean = Dataset(copy).verify()
    assert clean.ok and clean.checked == listed and not clean.problems and not clean.unhashed
    data = Dataset(copy)
    altered = copy / f"{VIEW}.rgb.png"
    payload = bytearray(altered.read_bytes())
    payload[-20] ^= 0x01  # same size: only the hash can tell
    altered.write_bytes(bytes(payload))
    truncated = copy / "samples/0000/000001_02.flow.exr"
    truncated.write_bytes(truncated.read_bytes()[:100])
    result = data.verify()
    assert not result.ok and result.checked == listed
    assert set(result.problems) == {f"{VIEW}.rgb.png", "samples/0000/000001_02.flow.exr"}
    assert "000000_00.rgb.png: BLAKE3" in result.problems[f"{VIEW}.rgb.png"]
    assert "the manifest's hashes say" in result.problems[f"{VIEW}.rgb.png"]
    assert "000001_02.flow.exr: 100 bytes" in result.problems["samples/0000/000001_02.flow.exr"]
    assert "000000_00.rgb.png" in str(result)


def test_the_hashes_shmgen_writes_match_its_files(box):
    entries = manifest_lines(box)
    if not any("hashes" in entry for entry in entries):
        pytest.skip("this shmgen binary does not write content hashes yet")
    result = Dataset(box).verify()
    assert result.ok and result.checked == sum(len(set(entry["files"])) for entry in entries), str(result)


def test_a_dataset_without_hashes_reads_and_says_what_verify_could_not_check(copy):
    entries = manifest_lines(copy)  # without hashes, as an older shmgen wrote it
    data = Dataset(copy)
    assert data[0].depth.shape == (120, 160)
    result = data.verify()
    assert result.checked == 0 and not result.problems and not result.ok
    assert len(result.unhashed) == sum(len(set(entry["files"])) for entry in entries)


@pytest.mark.parametrize("change, message", [
    (lambda h, f: h.pop(f), "has no hash for"),
    (lambda h, f: h[f].update(blake3="ABC"), "64 lowercase hex"),
    (lambda h, f: h[f].update(bytes=-1), "int ≥ 0"),
    (lambda h, f: h.update({f: "ABC"}), "not {"),
])
def test_malformed_hashes_are_refused(copy, change, message):
    add_hashes(copy)
    entries = manifest_lines(copy)
    change(entries[0]["hashes"], entries[0]["files"][0])
    write_manifest(copy, entries)
    with pytest.raises(ValueError, match=rf"manifest.jsonl: line 1: .*{message}"):
        Dataset(copy)


def test_a_sample_count_from_run_json_is_not_counted_up_to(copy):
    run = json.loads((copy / "run.json").read_text())
    run["dataset"]["samples"] = 10**15
    (copy / "run.json").write_text(json.dumps(run))
    with deadline(10), pytest.raises(ValueError, match=rf"lists 2 of {10**15} samples \(sample 2 is missing\)"):
        Dataset(copy)
    assert len(Dataset(copy, complete=False).samples) == 2
