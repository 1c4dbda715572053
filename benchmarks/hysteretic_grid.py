"""Does the hysteretic LPV input's candidate grid matter? Generalisation with a wide grid.

The default grid of the hysteretic input (stroke scale 0.05 / 0.1 / 0.2 mm x pre-yield share
0.25 / 0.5, ``mrdamper.models.lpv.inputs``) was narrowed after a prototype sweep that was also
scored on the generalisation test sets. This script reruns the LPV column of
``benchmarks/generalisation.py`` with a wide grid fixed a priori (stroke scale 0.02, 0.05, 0.1,
0.2, 0.5, 1 and 2 mm x share 0.25, 0.5 and 0.75: 21 candidates), still chosen on the training
records only (``choose_on="training"``, the estimator's default when this was measured;
``mrdamper.models.lpv.choice``).
If the choice falls inside the narrow grid, the scores are the same and the narrowing has no effect
on the results.

Run::

    OPENBLAS_NUM_THREADS=1 python benchmarks/hysteretic_grid.py            # every scenario
    OPENBLAS_NUM_THREADS=1 python benchmarks/hysteretic_grid.py --quick    # short rig records
"""

from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from mrdamper.models.lpv import inputs as _lpv_inputs

#: The a-priori wide grid: stroke scales [m] and pre-yield shares [-].
WIDE_STROKES = (2e-5, 5e-5, 1e-4, 2e-4, 5e-4, 1e-3, 2e-3)
WIDE_BLENDS = (0.25, 0.5, 0.75)


def main(argv: list[str] | None = None) -> None:
    """Run the LPV column of the generalisation benchmark with the wide grid."""
    import generalisation

    _lpv_inputs.STROKES = WIDE_STROKES
    _lpv_inputs.BLENDS = WIDE_BLENDS
    args = list(sys.argv[1:] if argv is None else argv)
    generalisation.main([*args, "--models", "lpv", "--lpv-choose-on", "training"])


if __name__ == "__main__":
    main()
