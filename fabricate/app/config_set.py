"""``--set KEY=VALUE``: overrides applied to a config's data before validation.

How each command treats commas (documented in the README and configs/reference.yaml):

- a key that takes a list (``offset.distances``, ``optimize.fixed``,
  ``input.side``): ``--set offset.distances=0,-200`` is the list ``[0, -200]``,
  in ``fabricate run`` and ``fabricate batch`` alike;
- any other key: the commas separate the values of a sweep
  (``parts.glass_thickness=8,10,12``), which ``fabricate batch`` runs as one job
  per value and ``fabricate run`` refuses naming batch;
- a sweep of a list key brackets each list: ``offset.distances=[0,-200],[0,-300]``;
- ``KEY=null`` removes the key: its default applies (``--set parts.beam_depth=null`` while
  sweeping ``offset.distances``).

Values are YAML (:func:`fabricate.app.config_yaml.parse_value`), as strict as a file's.
"""
from __future__ import annotations

from pathlib import Path
from typing import Any, get_args, get_origin

from pydantic import BaseModel

from optimize.errors import ConfigError

from .config_errors import printable, short
from .config_yaml import MAX_DEPTH, parse_value


def set_key(data: dict[str, Any], dotted: str, value: Any, *, source: str | Path = "--set") -> None:
    """Set ``data["a"]["b"] = value`` for ``dotted = "a.b"``, creating sections as needed;
    ``value = None`` removes the key (every key's ``null`` means its default)."""
    parts = [p for p in dotted.split(".")]
    if not dotted or any(not p for p in parts) or len(parts) > MAX_DEPTH:
        raise ConfigError(f"{source}: --set {short(dotted)}={short(value)}: expected a key path like "
                          "parts.glass_thickness")
    node = data
    for i, key in enumerate(parts[:-1]):
        child = node.get(key)
        if child is None:
            child = node[key] = {}
        if not isinstance(child, dict):
            raise ConfigError(f"{source}: --set {short(dotted)}: {printable('.'.join(parts[:i + 1]))[:200]} is {short(child)}, "
                              "not a section with keys")
        node = child
    if value is None:  # --set KEY=null: as if the file did not give the key (its default applies)
        node.pop(parts[-1], None)
    else:
        node[parts[-1]] = value


def takes_list(dotted: str, model: type[BaseModel]) -> bool:
    """Whether the key ``dotted`` (``offset.distances``) of the config ``model`` (``RunConfig``) takes a
    list of values."""
    cls: Any = model
    parts = dotted.split(".")
    for i, key in enumerate(parts):
        fields = cls.model_fields
        name = next((n for n, f in fields.items() if key in (n, f.alias)), None)
        if name is None:
            return False
        annotation = fields[name].annotation
        if i == len(parts) - 1:
            return _has_list(annotation)
        cls = next((a for a in _flatten(annotation) if isinstance(a, type) and issubclass(a, BaseModel)), None)
        if cls is None:
            return False
    return False


def _flatten(annotation) -> list:
    out, stack = [], [annotation]
    while stack:
        a = stack.pop()
        out.append(a)
        stack.extend(get_args(a))
    return out


def _has_list(annotation) -> bool:
    return any(a in (list, tuple) or get_origin(a) in (list, tuple) for a in _flatten(annotation))


def override_values(key: str, texts: list[str], model: type[BaseModel]) -> list[Any]:
    """The values of ``--set key=a,b,...`` (``texts``: the comma-separated parts, unparsed) for the
    config ``model``.

    A key that takes a list and parts that are not themselves lists in brackets:
    one value, the list (``offset.distances=0,-200`` -> ``[[0, -200]]``).
    Otherwise one value per part (``parts.glass_thickness=8,10`` -> ``[8, 10]``:
    a sweep, which ``fabricate batch`` runs and ``fabricate run`` refuses).
    """
    if len(texts) > 1 and takes_list(key, model) and not any(t.strip().startswith(("[", "(")) for t in texts):
        return [[parse_value(t) for t in texts]]
    return [parse_value(t) for t in texts]
