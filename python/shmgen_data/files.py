"""A dataset's files opened as untrusted input: no links followed, regular files only,
bounded reads.

A dataset handed to the loader may come from anywhere (a download, a shared drive), so every
file it reads (``run.json``, ``manifest.jsonl``, the view records, images and meshes) is
opened here, under these rules:

* The file is named relative to the dataset root, by a path with no ``..``, ``.`` or empty
  component, no backslash and no leading ``/`` (:func:`check_relative`). The root itself, as
  the user names it, may be a link; nothing below it may be: every folder between the root
  and the file is opened with ``O_DIRECTORY | O_NOFOLLOW`` relative to its parent's
  descriptor, and the file with ``O_NOFOLLOW | O_NONBLOCK`` (so a FIFO does not block the
  open), then ``fstat`` of the opened descriptor must say a regular file (a device such as
  ``/dev/zero``, a FIFO or a socket is refused before a byte is read).
* Its size is known before reading (``fstat``) and must be within the bound for its kind
  (:class:`Limits`), and equal to the manifest's ``hashes`` entry when the manifest has one;
  then exactly that many bytes are read, so a file growing meanwhile is noticed, not followed.

Errors are :class:`DatasetError` (a ``ValueError``) naming the file and what is wrong, or
``FileNotFoundError`` naming a file that is not there.

Platforms without ``dir_fd`` support (Windows) check each component with ``lstat`` instead
and compare the opened file's identity with what ``lstat`` saw.
"""

from __future__ import annotations

import errno
import json
import os
import re
import stat
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Iterable, Iterator, NoReturn

__all__ = ["DatasetError", "Limits", "FileHash", "DatasetFiles", "check_relative", "read_named"]

_MIB = 1 << 20
_GIB = 1 << 30


class DatasetError(ValueError):
    """A dataset's file breaks the rules (a link, not a regular file, over its size bound,
    a header or values its record does not allow, a hash mismatch); the message names the
    file and what is wrong."""


@dataclass(frozen=True)
class Limits:
    """The bounds on what the loader reads, per kind of file (bytes unless said otherwise).

    ``record_bytes`` bounds ``run.json`` and each view's JSON record; ``manifest_line_bytes``
    one line of ``manifest.jsonl`` and ``manifest_bytes`` the whole file; ``mesh_bytes`` a
    PLY file (meshes, points). An image may have at most
    ``image_factor × width × height × channels × bytes per sample + image_slack`` bytes
    (:meth:`image_bytes`), its size taken from the view's camera: twice the raw pixels covers
    deflate's and OpenEXR's worst case on incompressible data and the chunk tables, the slack
    the headers. ``max_side`` bounds an image's width and height (the recipe's own limit is
    16384). A file read on its own (:func:`shmgen_data.read_png`…), without a view to size it,
    is bounded by ``image_file_bytes``.
    """

    record_bytes: int = 64 * _MIB
    manifest_line_bytes: int = 64 * _MIB
    manifest_bytes: int = 16 * _GIB
    mesh_bytes: int = 4 * _GIB
    image_file_bytes: int = 2 * _GIB
    image_factor: int = 2
    image_slack: int = _MIB
    max_side: int = 16384

    def image_bytes(self, width: int, height: int, channels: int, sample_bytes: int) -> int:
        """The most bytes an image of that size may have, as a file or decoded."""
        return self.image_factor * width * height * channels * sample_bytes + self.image_slack


@dataclass(frozen=True)
class FileHash:
    """One file's entry of a manifest line's ``hashes``: its size and BLAKE3 (hex)."""

    bytes: int
    blake3: str


_HEX64 = re.compile(r"[0-9a-f]{64}")


def check_relative(relative: object, where: str) -> tuple[str, ...]:
    """The components of ``relative``, a path from a manifest; :class:`DatasetError` (saying
    ``where`` it was found) if it could name something outside the dataset or is not plain."""
    if not isinstance(relative, str):
        raise DatasetError(f"{where}: a file name must be a string, not {relative!r}")
    parts = tuple(relative.split("/"))
    bad = (relative.startswith("/") or "\\" in relative or "\0" in relative
           or any(part in ("", ".", "..") for part in parts))
    if bad:
        raise DatasetError(
            f"{where}: {relative!r} is not a plain relative path inside the dataset "
            "(no '..', '.', empty components, backslashes or leading '/')"
        )
    return parts


def parse_hashes(value: object, files: list[str], where: str) -> dict[str, FileHash]:
    """The entries of ``files`` in a manifest line's ``hashes`` object, checked: one for each,
    with a non-negative integer ``bytes`` and 64 lowercase hex digits (entries for files the
    line does not list are never used, so they are left out)."""
    if not isinstance(value, dict):
        raise DatasetError(f"{where}: 'hashes' is not an object")
    missing = [relative for relative in files if relative not in value]
    if missing:
        raise DatasetError(f"{where}: 'hashes' has no hash for {missing[0]!r}")
    hashes = {}
    for relative in files:
        entry = value[relative]
        size = entry.get("bytes") if isinstance(entry, dict) else None
        digest = entry.get("blake3") if isinstance(entry, dict) else None
        if type(size) is not int or size < 0 or not isinstance(digest, str) or not _HEX64.fullmatch(digest):
            raise DatasetError(
                f"{where}: the hash of {relative!r} is not {{\"bytes\": <int ≥ 0>, \"blake3\": <64 lowercase hex>}}: {entry!r}"
            )
        hashes[relative] = FileHash(size, digest)
    return hashes


def _refuse_constant(name: str) -> NoReturn:
    raise ValueError(f"{name} is not a JSON number")


def parse_json(data: bytes, shown: str) -> dict[str, Any]:
    """``data`` parsed as a JSON object (NaN and Infinity refused: shmgen never writes them)."""
    try:
        value = json.loads(data, parse_constant=_refuse_constant)
    except (ValueError, RecursionError) as error:  # JSONDecodeError, UnicodeDecodeError are ValueErrors
        raise DatasetError(f"{shown}: does not parse as JSON ({error})") from None
    if not isinstance(value, dict):
        raise DatasetError(f"{shown}: a JSON object is expected, it holds {type(value).__name__}")
    return value


# ---------------------------------------------------------------------------------------
# Opening without links

_O = {name: getattr(os, name, 0) for name in
      ("O_CLOEXEC", "O_NOFOLLOW", "O_NONBLOCK", "O_NOCTTY", "O_DIRECTORY", "O_BINARY")}
#: Whether folders can be walked by descriptor (POSIX); else components are checked by lstat.
_DIR_FD = (os.open in os.supports_dir_fd and os.stat in os.supports_dir_fd
           and bool(_O["O_NOFOLLOW"]) and bool(_O["O_DIRECTORY"]))
_FILE_FLAGS = os.O_RDONLY | _O["O_NOFOLLOW"] | _O["O_NONBLOCK"] | _O["O_NOCTTY"] | _O["O_CLOEXEC"] | _O["O_BINARY"]
_DIR_FLAGS = os.O_RDONLY | _O["O_DIRECTORY"] | _O["O_NOFOLLOW"] | _O["O_CLOEXEC"]


def _what_is(mode: int) -> str:
    if stat.S_ISLNK(mode):
        return "a symbolic link (links are not followed inside a dataset)"
    if stat.S_ISDIR(mode):
        return "a folder"
    if stat.S_ISFIFO(mode):
        return "a FIFO"
    if stat.S_ISCHR(mode) or stat.S_ISBLK(mode):
        return "a device"
    if stat.S_ISSOCK(mode):
        return "a socket"
    return "not a regular file"


def _refuse(shown: str, mode: int, expected: str = "a regular file") -> NoReturn:
    raise DatasetError(f"{shown}: is {_what_is(mode)}, {expected} is expected")


def _failed_open(error: OSError, name: str, dir_fd: int, shown: str, expected: str) -> OSError | DatasetError:
    """The clear error for an ``open`` of ``name`` in the folder ``dir_fd`` that failed: what
    is there instead, or that nothing is."""
    if error.errno == errno.ENOENT:
        return FileNotFoundError(f"{shown}: no such file")
    try:
        info = os.stat(name, dir_fd=dir_fd, follow_symlinks=False)
    except OSError:
        return DatasetError(f"{shown}: cannot be opened ({error.strerror})")
    return DatasetError(f"{shown}: is {_what_is(info.st_mode)}, {expected} is expected")


class DatasetFiles:
    """The files below one dataset root, opened by the rules of this module.

    ``hashes`` (relative path → :class:`FileHash`) holds the manifest's entries, when it has
    them; a file with one must have that size before it is read.
    """

    def __init__(self, root: str | os.PathLike[str], limits: Limits | None = None):
        self.root = Path(root)
        self.limits = limits or Limits()
        self.hashes: dict[str, FileHash] = {}

    def shown(self, relative: str) -> str:
        """How errors name the file ``relative``."""
        return str(self.root / relative)

    def _open_root(self) -> int:
        # The root as the user names it: a link to it is fine.
        return os.open(self.root, os.O_RDONLY | _O["O_DIRECTORY"] | _O["O_CLOEXEC"])

    def _folder(self, parent: int, name: str, shown: str) -> int:
        """The sub-folder ``name`` of the folder ``parent``, opened without following links."""
        try:
            return os.open(name, _DIR_FLAGS, dir_fd=parent)
        except OSError as error:
            raise _failed_open(error, name, parent, shown, "a folder") from None

    def _open_fd(self, parts: tuple[str, ...]) -> int:
        """A descriptor of the regular file at ``parts`` below the root (walked by descriptor)."""
        shown = self.shown("/".join(parts))
        folder = self._open_root()
        try:
            for depth, name in enumerate(parts[:-1]):
                inner = self._folder(folder, name, self.shown("/".join(parts[: depth + 1])))
                os.close(folder)
                folder = inner
            try:
                fd = os.open(parts[-1], _FILE_FLAGS, dir_fd=folder)
            except OSError as error:
                raise _failed_open(error, parts[-1], folder, shown, "a regular file") from None
        finally:
            os.close(folder)
        return fd

    def _lstat_walk(self, parts: tuple[str, ...]) -> os.stat_result:
        """Without ``dir_fd``: ``lstat`` of each component (folders, then a regular file)."""
        path = self.root
        for depth, name in enumerate(parts):
            path = path / name
            shown = self.shown("/".join(parts[: depth + 1]))
            try:
                info = os.lstat(path)
            except FileNotFoundError:
                raise FileNotFoundError(f"{shown}: no such file") from None
            last = depth == len(parts) - 1
            if not (stat.S_ISREG(info.st_mode) if last else stat.S_ISDIR(info.st_mode)):
                _refuse(shown, info.st_mode, "a regular file" if last else "a folder")
        return info

    def _open_fd_by_lstat(self, parts: tuple[str, ...]) -> int:
        """Without ``dir_fd``: the components checked by :meth:`_lstat_walk`, then the file's
        identity compared after opening (a swap in between is refused)."""
        seen = self._lstat_walk(parts)
        fd = os.open(self.root.joinpath(*parts), _FILE_FLAGS)
        opened = os.fstat(fd)
        if (opened.st_dev, opened.st_ino) != (seen.st_dev, seen.st_ino):
            os.close(fd)
            raise DatasetError(f"{self.shown('/'.join(parts))}: was replaced while being opened")
        return fd

    def open(self, relative: str, limit: int, what: str) -> "OpenFile":
        """``relative`` opened for reading: a regular file no larger than ``limit`` (the
        bound for ``what``, named in the error) and of its hashed size, if it has one."""
        parts = check_relative(relative, str(self.root))
        fd = self._open_fd(parts) if _DIR_FD else self._open_fd_by_lstat(parts)
        opened = OpenFile(fd, self.shown(relative))
        try:
            opened.check_size(limit, what, self.hashes.get(relative))
        except BaseException:
            opened.close()
            raise
        return opened

    def read(self, relative: str, limit: int, what: str) -> bytes:
        """Every byte of ``relative`` (see :meth:`open`)."""
        with self.open(relative, limit, what) as opened:
            return opened.read_all()

    def read_json(self, relative: str) -> dict[str, Any]:
        """``relative`` as a JSON object, within ``Limits.record_bytes``."""
        data = self.read(relative, self.limits.record_bytes, "a JSON record (Limits.record_bytes)")
        return parse_json(data, self.shown(relative))

    def hash_problem(self, relative: str) -> str | None:
        """What is wrong with ``relative`` against its entry in ``hashes`` (its size, then its
        BLAKE3, read in chunks), or None if it matches."""
        import blake3

        expected = self.hashes[relative]
        hasher = blake3.blake3()
        try:
            with self.open(relative, expected.bytes, "its hashed size") as opened:
                for piece in opened.chunks():
                    hasher.update(piece)
        except (DatasetError, OSError) as error:
            return str(error)
        digest = hasher.hexdigest()
        if digest != expected.blake3:
            return f"{self.shown(relative)}: BLAKE3 {digest}, the manifest's hashes say {expected.blake3} (altered)"
        return None

    def check_listed(self, relatives: Iterable[str]) -> None:
        """Each of ``relatives`` is a plain path to a regular file (not a link, nor below one)
        of its hashed size: the cheap check of a whole manifest, by ``lstat`` through folders
        opened once each."""
        folders: dict[tuple[str, ...], int] = {}
        try:
            for relative in relatives:
                parts = check_relative(relative, str(self.root))
                try:
                    if _DIR_FD:
                        folder = self._cached_folder(parts[:-1], folders)
                        info = os.stat(parts[-1], dir_fd=folder, follow_symlinks=False)
                    else:
                        info = self._lstat_walk(parts)
                except FileNotFoundError:
                    raise DatasetError(f"{self.root}: {relative} is listed in manifest.jsonl but missing") from None
                if not stat.S_ISREG(info.st_mode):
                    _refuse(self.shown(relative), info.st_mode)
                _check_hashed_size(self.shown(relative), info.st_size, self.hashes.get(relative))
        finally:
            for fd in folders.values():
                os.close(fd)

    def _cached_folder(self, parts: tuple[str, ...], folders: dict[tuple[str, ...], int]) -> int:
        """The folder at ``parts`` below the root, opened without links and kept in ``folders``."""
        if parts not in folders:
            if parts:
                parent = self._cached_folder(parts[:-1], folders)
                folders[parts] = self._folder(parent, parts[-1], self.shown("/".join(parts)))
            else:
                folders[parts] = self._open_root()
        return folders[parts]


def _check_hashed_size(shown: str, size: int, expected: FileHash | None) -> None:
    if expected is not None and size != expected.bytes:
        raise DatasetError(
            f"{shown}: {size} bytes, the manifest's hashes say {expected.bytes} (truncated or altered)"
        )


class OpenFile:
    """An opened regular file of known size, read within its bound."""

    def __init__(self, fd: int, shown: str):
        self.fd = fd
        self.shown = shown
        info = os.fstat(fd)
        if not stat.S_ISREG(info.st_mode):  # a FIFO or device under a regular name, or a race
            os.close(fd)
            _refuse(shown, info.st_mode)
        self.size = info.st_size

    def __enter__(self) -> "OpenFile":
        return self

    def __exit__(self, *_: object) -> None:
        self.close()

    def close(self) -> None:
        if self.fd >= 0:
            os.close(self.fd)
            self.fd = -1

    def check_size(self, limit: int, what: str, expected: FileHash | None = None) -> None:
        """The file is at most ``limit`` bytes (the bound for ``what``) and of its hashed size."""
        _check_hashed_size(self.shown, self.size, expected)
        if self.size > limit:
            raise DatasetError(f"{self.shown}: {self.size} bytes, more than the {limit} allowed for {what}")

    def chunks(self, chunk: int = 4 * _MIB) -> Iterator[bytes]:
        """The file's bytes in order, ``self.size`` of them and no more; :class:`DatasetError`
        if it is shorter or longer now than when opened."""
        left = self.size
        while left > 0:
            piece = os.read(self.fd, min(chunk, left))
            if not piece:
                raise DatasetError(f"{self.shown}: shrank while being read ({self.size - left} of {self.size} bytes)")
            left -= len(piece)
            yield piece
        if os.read(self.fd, 1):
            raise DatasetError(f"{self.shown}: grew while being read (more than {self.size} bytes)")

    def read_all(self) -> bytes:
        return b"".join(self.chunks())

    def lines(self, line_limit: int, what: str) -> Iterator[bytes]:
        """The file's complete lines (ending in a newline), each at most ``line_limit``
        bytes; what follows the last newline (a line being appended) is left out."""
        pending = b""
        for piece in self.chunks():
            pending += piece
            lines = pending.split(b"\n")
            pending = lines.pop()
            for line in [*lines, pending]:
                if len(line) > line_limit:
                    raise DatasetError(f"{self.shown}: a line longer than the {line_limit} bytes allowed for {what}")
            yield from lines
        # `pending` is a torn append, or empty.


def read_named(path: str | os.PathLike[str], limit: int, what: str) -> tuple[bytes, str]:
    """The bytes of a file the user names (links followed: the user chose it), a regular
    file of at most ``limit`` bytes; and how errors name it."""
    shown = str(path)
    try:
        fd = os.open(path, os.O_RDONLY | _O["O_NONBLOCK"] | _O["O_NOCTTY"] | _O["O_CLOEXEC"] | _O["O_BINARY"])
    except FileNotFoundError:
        raise FileNotFoundError(f"{shown}: no such file") from None
    except IsADirectoryError:
        raise DatasetError(f"{shown}: is a folder, a regular file is expected") from None
    with OpenFile(fd, shown) as opened:
        opened.check_size(limit, what)
        return opened.read_all(), shown
