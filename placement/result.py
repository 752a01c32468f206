"""The result convention of the optimizers, modelled on ``scipy.optimize.OptimizeResult``.

Every optimizer result is a frozen dataclass with

* ``anchors`` (M, 3) m, the layout, and ``x`` (3M,), the same numbers flattened;
* a cost field whose name carries its unit (``cost_m2``, ``objective_m``, ...) and ``fun``,
  that cost (the class names its field in ``FUN``);
* ``success`` (bool), ``status`` (int code; each class documents its table in ``STATUS``,
  code → meaning) and ``message`` (text);
* ``nit`` and ``nfev`` (iterations and cost evaluations) where they mean something;
* ``to_dict()``, a JSON-ready dictionary of every field plus ``fun``.

:class:`LayoutResult` is the mixin that provides ``x``, ``fun``, ``describe_status`` and
``to_dict``.
"""

from __future__ import annotations

import dataclasses
from typing import Any, ClassVar

import numpy as np

from placement.serialization import to_jsonable


class LayoutResult:
    """Mixin for frozen dataclasses with the fields ``anchors``, ``success``, ``status``,
    ``message`` and the cost field named by ``FUN``."""

    #: name of the cost field (its unit in the name), returned by :attr:`fun`
    FUN: ClassVar[str] = ""
    #: status code → meaning
    STATUS: ClassVar[dict[int, str]] = {}

    @property
    def x(self) -> np.ndarray:
        """(3M,) the anchors flattened, as scipy's ``OptimizeResult.x``."""
        return np.asarray(self.anchors, dtype=float).ravel()

    @property
    def fun(self) -> float:
        """The cost of the result, in the unit its field ``FUN`` names."""
        return getattr(self, self.FUN)

    def describe_status(self) -> str:
        """The meaning of :attr:`status` from the class's ``STATUS`` table."""
        return self.STATUS.get(self.status, "unknown status")

    def to_dict(self) -> dict[str, Any]:
        """Plain JSON-serializable dictionary: every field (arrays as lists; non-finite
        floats kept) and ``fun``."""
        out = {f.name: to_jsonable(getattr(self, f.name), strict=False)
               for f in dataclasses.fields(self)}  # fmt: skip
        out["fun"] = to_jsonable(self.fun, strict=False)
        return out
