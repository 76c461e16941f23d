"""``F``: the one constructor of schema fields of the scene model (:mod:`vlref.scene.model`,
:mod:`vlref.scene.technique_params`); :mod:`vlref.scene.schema` reads the metadata it stores."""

from __future__ import annotations

import dataclasses
from dataclasses import field

__all__ = ["F"]


def F(default=dataclasses.MISSING, doc: str = "", **meta):
    """A dataclass field with documentation (``doc``) and schema constraints in its metadata; mutable
    defaults go through ``factory=``."""
    meta["doc"] = doc
    if isinstance(default, (list, dict)) or (dataclasses.is_dataclass(default) and not isinstance(default, type)):
        raise TypeError("use factory= for mutable defaults")
    factory = meta.pop("factory", None)
    if factory is not None:
        return field(default_factory=factory, metadata=meta)
    return field(default=default, metadata=meta)
