"""Where a study's numbers come from: the mrdamper version, the commit of its source when it runs
from a git checkout, and a summary of the settings.

:func:`provenance` is stored in ``StudyResult.info["provenance"]``, so it is written to
``study.json`` and shown at the top of ``report.html``. It holds no time and no host name: two
identical runs give the same provenance, byte for byte.
"""

from __future__ import annotations

import sys
from typing import Any

from mrdamper.study.protocol import ModelSpec, Protocol
from mrdamper.version import git_commit

__all__ = ["git_commit", "provenance", "records_text"]


def provenance(protocol: Protocol, specs: tuple[ModelSpec, ...], seed: int) -> dict[str, Any]:
    """The provenance of a study run with ``protocol``, models ``specs`` and ``seed``.

    Parameters
    ----------
    protocol : Protocol
        The protocol run.
    specs : tuple of ModelSpec
        The models run.
    seed : int
        The study seed.

    Returns
    -------
    dict
        ``mrdamper_version``, ``git_commit`` (None outside a git checkout) and ``settings``:
        protocol name, electrical input, split, range policy, seed and each model's settings.
    """
    # the package itself is always loaded before this module (importing it would be a circle)
    version = str(getattr(sys.modules["mrdamper"], "__version__", "unknown"))
    return {
        "mrdamper_version": version,
        "git_commit": git_commit(),
        "settings": {
            "protocol": protocol.name,
            "input": protocol.input,
            "split": protocol.split.describe(),
            "range_policy": protocol.range_policy,
            "seed": int(seed),
            "models": {s.label: {"kind": s.kind, **protocol.settings_for(s)} for s in specs},
        },
    }


def records_text(n_records: Any, origin: str) -> str:
    """``"61 records from the virtual rig (Spencer damper model)"`` or ``"12 measured records"``.

    Parameters
    ----------
    n_records : int
        Number of records.
    origin : str
        :func:`~mrdamper.study.runner.data_origin` of the records.
    """
    noun = "record" if n_records == 1 else "records"
    if origin.startswith("virtual rig"):
        damper = origin[origin.find("(") + 1 : origin.rfind(" damper)")] if "(" in origin else ""
        model = f" ({damper} damper model)" if damper and damper != "unknown" else ""
        return f"{n_records} {noun} from the virtual rig{model}"
    if origin == "measured":
        return f"{n_records} measured {noun}"
    return f"{n_records} {noun} ({origin or 'origin not recorded'})"
