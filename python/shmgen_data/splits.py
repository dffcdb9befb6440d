"""Train/test splits of a dataset's views, whole groups at a time, the same on every call
and every machine.

Owns: the keys views are grouped by and the rule that picks the held-out groups. Must not
touch: files (views read their own records).

A split groups the views by a key and sends each group whole to one side, so that nothing of
a held-out group (the other views of a sample, its augmented copies, another view of the same
prompt) leaks into training. The key, ``by``:

* a name: ``"sample"`` (the sample index; the default), ``"prompt"`` (the first structure's
  texture prompt), ``"support"`` (its support: ``"simply_supported"``, ``"cantilever"``…),
  ``"structure"`` (its kind, or an assembly's name), ``"loads"`` (its load case: the loads
  of its record, as JSON);
* a dotted path into the view's record, as ``shmgen eval --where`` reads it
  (``"scene.structures.0.section.width"``); a view whose record lacks it has the key None;
* a function of the :class:`View`, returning anything JSON can write (or any value whose
  ``str`` is stable across runs).

Which groups are held out: ``holdout=`` a key value, or a list of them (``holdout="A photo of
cracked timber for construction"``); or ``fraction=f``, the ⌊f · n + ½⌋ groups of the n (at
least one, never all) that come first when the groups are ordered by the BLAKE2b hash of
``"{seed}\\0{key as JSON}"``, ties by that JSON. The hash is of the key's text, not Python's
``hash`` (salted per process), so the split depends on the keys and the seed alone: not on
the order of the views, the machine, or the Python version.
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Callable

from .structures import Record

if TYPE_CHECKING:
    from .dataset import Dataset, View

__all__ = ["Split", "split", "KEYS", "record_field"]


def _first_structure(view: View) -> Record:
    structures = view.record.get("scene", {}).get("structures") or [{}]
    first = structures[0]
    return first if isinstance(first, dict) else {}


def _structure_name(view: View) -> Any:
    first = _first_structure(view)
    return first.get("name") if first.get("kind") == "assembly" else first.get("kind")


def _sample(view: View) -> int:
    return view.sample


#: The named keys of ``by``.
KEYS: dict[str, Callable[[View], Any]] = {
    "sample": _sample,
    "prompt": lambda view: view.prompt,
    "support": lambda view: _first_structure(view).get("support"),
    "structure": _structure_name,
    "loads": lambda view: _first_structure(view).get("loads"),
}


def record_field(record: Any, path: str) -> Any:
    """The value at the dotted ``path`` of a record (objects by key, lists by index); None
    where the record lacks it."""
    value = record
    for key in path.split("."):
        if isinstance(value, dict):
            value = value.get(key)
        elif isinstance(value, list) and key.isdigit() and int(key) < len(value):
            value = value[int(key)]
        else:
            return None
    return value


@dataclass
class Split:
    """The two sides of a split: ``train`` and ``test`` views (dataset order), their positions
    in the dataset (``train_indices``, ``test_indices``: for ``torch.utils.data.Subset``), the
    key (``by``) and the key values held out (``held_out``, in the order of the rule)."""

    train: list[View]
    test: list[View]
    train_indices: list[int]
    test_indices: list[int]
    by: str
    held_out: list[Any]

    def __repr__(self) -> str:
        return f"Split(by={self.by!r}, train={len(self.train)} views, test={len(self.test)} views, held_out={self.held_out!r})"


def _text(key: Any) -> str:
    """The key as stable text: JSON with sorted keys, else its ``str``."""
    try:
        return json.dumps(key, sort_keys=True, ensure_ascii=False)
    except (TypeError, ValueError):
        return str(key)


def _drawn(keys: list[str], fraction: float, seed: int) -> set[str]:
    """The keys (texts) held out by ``fraction`` (see the module)."""
    if not 0 < fraction < 1:
        raise ValueError(f"fraction={fraction}: expected a share between 0 and 1, e.g. 0.05")
    if len(keys) < 2:
        raise ValueError(f"a split needs at least two groups; the views have {len(keys)}")
    count = min(max(int(fraction * len(keys) + 0.5), 1), len(keys) - 1)
    order = sorted(keys, key=lambda k: (hashlib.blake2b(f"{seed}\0{k}".encode(), digest_size=8).digest(), k))
    return set(order[:count])


def split(dataset: Dataset, by: str | Callable[[View], Any] = "sample", *, holdout: Any = None,
          fraction: float | None = None, seed: int = 0) -> Split:
    """The views of ``dataset`` split by ``by``, the groups ``holdout`` names (or ``fraction``
    of them, drawn by ``seed``) on the test side: see the module. ``ValueError`` when both or
    neither of ``holdout`` and ``fraction`` are given, or when a held-out value matches no
    view (a typo would otherwise hold out nothing)."""
    if (holdout is None) == (fraction is None):
        raise ValueError("give holdout= (the key values held out) or fraction= (a share of the groups), not both")
    if callable(by):
        key, name = by, getattr(by, "__name__", "function")
    elif by in KEYS:
        key, name = KEYS[by], by
    else:
        path = str(by)
        key, name = (lambda view: record_field(view.record, path)), path
    texts = [_text(key(view)) for view in dataset]
    if fraction is not None:
        test_keys = _drawn(sorted(set(texts)), fraction, seed)
    else:
        wanted = holdout if isinstance(holdout, (list, tuple, set, frozenset)) else [holdout]
        test_keys = {_text(value) for value in wanted}
        absent = sorted(test_keys - set(texts))
        if absent:
            known = ", ".join(sorted(set(texts))[:10])
            raise ValueError(f"holdout {', '.join(absent)}: no view has that {name}; the views have: {known}")
    test_indices = [i for i, text in enumerate(texts) if text in test_keys]
    train_indices = [i for i, text in enumerate(texts) if text not in test_keys]
    held = sorted(test_keys)
    return Split([dataset[i] for i in train_indices], [dataset[i] for i in test_indices],
                 train_indices, test_indices, name, [json.loads(t) if _is_json(t) else t for t in held])


def _is_json(text: str) -> bool:
    try:
        json.loads(text)
    except ValueError:
        return False
    return True
