"""What a view's record says about its scene and its making, as typed objects: the sample's
structures by name (with their labels and their ids in the segmentation images), and how an
augmented copy was made from its clean view.

Owns: reading ``scene.structures``, ``segmentation`` and ``augmentation`` of a
``shmgen.view/1`` record, and checking that they agree with each other and with the file
name. Must not touch: files (:mod:`shmgen_data.dataset` reads them) or pixels.

Structure names: an assembly has the name the recipe gave it (``assembly("silo", …)``); a
beam has none in the record, so it is named ``"beam"``. Where several structures of a sample
share a name, each is named ``"{name}#{k}"``, k = 0, 1, … in the record's order, so every
structure has one name and the names do not depend on anything but the record.
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np
from numpy.typing import NDArray

from .files import DatasetError

__all__ = ["Augmentation", "Structure", "Structures"]

#: A record's JSON object, as ``json.loads`` gives it.
Record = dict[str, Any]


@dataclass(frozen=True)
class Structure:
    """One structure of a sample, as the view's record describes it.

    ``name``: its unique name in the sample (see the module); ``kind``: ``"beam"`` or
    ``"assembly"``; ``index``: its place in the record's ``scene.structures``;
    ``instance_id``: its value in the ``instances`` image (index + 1, 0 is background);
    ``parts``: the names of its parts (``"beam"`` for a beam, its shapes' parts for an
    assembly) and ``part_ids`` their values in the ``parts`` image; ``labels``: what the
    mechanics found (``max_deflection``, ``loads``, ``theory``, …; None for an assembly);
    ``record``: its entry of ``scene.structures`` as written.
    """

    name: str
    kind: str
    index: int
    instance_id: int
    parts: tuple[str, ...]
    part_ids: tuple[int, ...]
    labels: Record | None
    record: Record

    @property
    def prompt(self) -> str | None:
        """The texture prompt the structure was painted from (``material.prompt`` of its
        record: ``"A photo of cracked timber for construction"``); None for a structure
        given a plain colour."""
        material = self.record.get("material")
        prompt = material.get("prompt") if isinstance(material, dict) else None
        return prompt if isinstance(prompt, str) else None

    def mask(self, instances: NDArray[np.integer[Any]]) -> NDArray[np.bool_]:
        """Where an ``instances`` image (``view.instances``) shows this structure."""
        return np.asarray(instances == self.instance_id)


class Structures(Mapping[str, Structure]):
    """A sample's structures by name, in the record's order (see the module for names):
    ``structures["silo"].instance_id``, ``list(structures)`` the names,
    ``structures.values()`` the :class:`Structure` objects."""

    def __init__(self, structures: list[Structure]):
        self._by_name = {s.name: s for s in structures}

    @classmethod
    def from_record(cls, record: Record, shown: str) -> Structures:
        """The structures of a ``shmgen.view/1`` record (``shown`` names it in errors),
        checked against its ``segmentation`` tables."""
        try:
            entries = record["scene"]["structures"]
            segmentation = record["segmentation"]
            part_ids: list[str] = segmentation["part_ids"]
            instance_ids: list[Record | None] = segmentation["instance_ids"]
            names = _names([_own_name(entry) for entry in entries])
            built = [_structure(entry, k, name, part_ids, instance_ids, shown)
                     for k, (entry, name) in enumerate(zip(entries, names))]
        except (KeyError, TypeError, IndexError) as error:
            raise DatasetError(f"{shown}: scene.structures and segmentation do not read as "
                               f"shmgen.view/1 states them ({type(error).__name__}: {error})") from None
        return cls(built)

    def __getitem__(self, name: str) -> Structure:
        try:
            return self._by_name[name]
        except KeyError:
            raise KeyError(f"no structure named {name!r}; the sample has {', '.join(map(repr, self)) or 'none'}") from None

    def __iter__(self) -> Iterator[str]:
        return iter(self._by_name)

    def __len__(self) -> int:
        return len(self._by_name)

    def __repr__(self) -> str:
        return f"Structures({list(self)})"

    def by_instance(self, instance_id: int) -> Structure:
        """The structure an ``instances`` image value names (``KeyError`` for 0, the
        background, the ground's id, or an unknown one)."""
        for structure in self.values():
            if structure.instance_id == instance_id:
                return structure
        raise KeyError(f"instance id {instance_id} is no structure (0 is the background; the structures have "
                       f"{', '.join(f'{s.name}: {s.instance_id}' for s in self.values())})")

    @property
    def labels(self) -> dict[str, Record | None]:
        """Each structure's labels by name (None for an assembly)."""
        return {name: structure.labels for name, structure in self.items()}

    @property
    def prompts(self) -> dict[str, str | None]:
        """Each structure's texture prompt by name (None for a plain colour)."""
        return {name: structure.prompt for name, structure in self.items()}


def _own_name(entry: Record) -> str:
    """A structure's name as the record has it: an assembly's ``name``, else its ``kind``."""
    name = entry["name"] if entry.get("kind") == "assembly" else entry["kind"]
    if not isinstance(name, str):
        raise TypeError(f"a structure's name is {name!r}, not text")
    return name


def _names(own: list[str]) -> list[str]:
    """Unique names: a name given once stays, a name given n > 1 times becomes name#0…#n-1."""
    seen: dict[str, int] = {}
    names = []
    for name in own:
        if own.count(name) == 1:
            names.append(name)
        else:
            names.append(f"{name}#{seen.get(name, 0)}")
            seen[name] = seen.get(name, 0) + 1
    return names


def _structure(entry: Record, index: int, name: str, part_ids: list[str],
               instance_ids: list[Record | None], shown: str) -> Structure:
    """Structure ``index`` of the record, its ids checked against the segmentation tables."""
    instance_id = index + 1
    instance = instance_ids[instance_id]
    if instance is None or instance.get("structure") != index:
        raise DatasetError(f"{shown}: segmentation.instance_ids[{instance_id}] is {instance!r}, "
                           f"not structure {index} ({name})")
    kind = entry["kind"]
    parts = ("beam",) if kind == "beam" else tuple(dict.fromkeys(s["part"] for s in entry["shapes"]))
    missing = [part for part in parts if part not in part_ids]
    if missing:
        raise DatasetError(f"{shown}: structure {name!r} has parts {missing} that segmentation.part_ids "
                           f"({part_ids}) does not list")
    labels = entry.get("labels")
    return Structure(name, kind, index, instance_id, parts, tuple(part_ids.index(p) for p in parts),
                     labels if isinstance(labels, dict) else None, entry)


@dataclass(frozen=True)
class Augmentation:
    """How an augmented copy was made from its clean view (the record's ``augmentation``).

    ``copy``: the copy's index (its files end in ``a{copy}``); ``mode``: ``"exact"`` (the
    camera was changed and the view rendered again: depth and labels exact) or ``"image"``
    (the rendered images were warped); ``operations``: each operation applied, in order, with
    the values drawn (``{"op": "warp", "zoom": …, "angle": …, "centre": …, "shift": …}``,
    ``{"op": "erase", "rects": …}``, ``{"op": "colour_jitter", …}``…).
    """

    copy: int
    mode: Literal["exact", "image"]
    operations: tuple[Record, ...]

    @property
    def geometric(self) -> bool:
        """Whether an operation moved pixels (``warp`` or ``crop``): if not, the copy's
        depth, masks and ids are its clean view's."""
        return any(op.get("op") in ("warp", "crop") for op in self.operations)

    @classmethod
    def from_record(cls, value: Any, shown: str) -> Augmentation:
        """The record's ``augmentation`` object (``shown`` names the record in errors)."""
        try:
            copy, mode, operations = value["copy"], value["mode"], value["operations"]
        except (KeyError, TypeError):
            raise DatasetError(f"{shown}: augmentation is {value!r}; copy, mode and operations are expected") from None
        if type(copy) is not int or mode not in ("exact", "image") or not isinstance(operations, list):
            raise DatasetError(f"{shown}: augmentation has copy {copy!r}, mode {mode!r}; "
                               "a copy index, \"exact\" or \"image\" and a list of operations are expected")
        return cls(copy, mode, tuple(operations))
