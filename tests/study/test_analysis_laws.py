"""The study's force-velocity analysis hands each LPV the laws its input asks for: post-yield
outer slopes for the default (hysteretic) input, the paper's regression for the paper's input."""

from __future__ import annotations

import numpy as np

from mrdamper.analysis import fit_zone_laws, zone_fits_by_level
from mrdamper.kinds import VARIANTS
from mrdamper.rig import VirtualRig, reference_damper
from mrdamper.study import ModelSpec, doe_protocol
from mrdamper.study.analysis_step import run_analysis
from mrdamper.study.runner import _settings


def _stepped_sines() -> list:
    """Rig sines at five currents, one current per record (the analysis pools them by level)."""
    rig = VirtualRig(damper=reference_damper("quiroz2022"), fs=1000.0)
    t = np.arange(3000) / 1000.0
    out = []
    for k, cur in enumerate((0.0, 0.25, 0.5, 0.75, 1.0)):
        for amp, f in ((0.01, 1.0), (0.002, 5.0)):
            x = amp * np.sin(2 * np.pi * f * t)
            out.append(
                rig.run(
                    x,
                    np.full(t.size, cur),
                    seed=10 * k + int(f),
                    name=f"s{amp}_{f}_{cur}",
                    metadata={"current": cur},
                )
            )
    return out


def test_each_lpv_gets_the_laws_of_its_input() -> None:
    from mrdamper.data import ExperimentSet

    records = ExperimentSet(_stepped_sines())
    outcome = run_analysis(records, "i")
    assert outcome.error == "" and outcome.laws is not None
    assert outcome.post_yield_laws is not None
    # the same laws as the analysis functions give with the post-yield option
    direct = fit_zone_laws(
        zone_fits_by_level(records, outer_slopes="post-yield"), degree=2, strict=False
    )
    np.testing.assert_array_equal(outcome.post_yield_laws.gamma_m, direct.gamma_m)
    rho = np.linspace(0.0, 1.0, 5)
    assert not np.allclose(outcome.post_yield_laws.m(rho), outcome.laws.m(rho), rtol=0.01)
    np.testing.assert_array_equal(outcome.post_yield_laws.m(rho)[:, 1], outcome.laws.m(rho)[:, 1])
    protocol = doe_protocol()
    paper = next(v for v in VARIANTS if v.kind == "lpv")
    default = _settings(ModelSpec("lpv"), protocol, 0, outcome)
    static = _settings(ModelSpec("lpv", dict(paper.settings), paper.label), protocol, 0, outcome)
    zones = _settings(ModelSpec("lpv", {"outer_slopes": "zones"}), protocol, 0, outcome)
    assert default["zone_laws"] is outcome.post_yield_laws
    assert static["zone_laws"] is outcome.laws
    assert zones["zone_laws"] is outcome.laws
    assert _settings(ModelSpec("sp1"), protocol, 0, outcome).get("zone_laws") is None


def test_without_post_yield_laws_every_lpv_gets_the_papers() -> None:
    from mrdamper.study import AnalysisOutcome

    paper, post = object(), object()
    assert AnalysisOutcome(laws=paper, post_yield_laws=None).laws_for("post-yield") is paper
    assert AnalysisOutcome(laws=paper, post_yield_laws=post).laws_for("post-yield") is post
    assert AnalysisOutcome(laws=paper, post_yield_laws=post).laws_for("zones") is paper
