"""An ordered, named collection of :class:`~mrdamper.data.Experiment` records.

Records are never concatenated into one signal: each keeps its own initial state, and every
estimator treats them as separate records.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Iterator, Sequence
from typing import Any, overload

import numpy as np
import pandas as pd

from mrdamper.data.experiment import Experiment
from mrdamper.errors import DataValidationError

__all__ = ["ExperimentSet", "as_experiment_set", "metadata_equal"]


class ExperimentSet(Sequence[Experiment]):
    """Ordered, immutable collection of uniquely named experiments.

    Parameters
    ----------
    experiments : iterable of Experiment
        The records; names must be unique.
    name : str
        Name of the set (e.g. the data folder).

    Examples
    --------
    >>> import numpy as np
    >>> t = np.arange(10) * 1e-3
    >>> a = Experiment(t=t, x=t, v=t, F=t, i=t * 0, name="a", metadata={"current": 0.0})
    >>> b = Experiment(t=t, x=t, v=t, F=t, i=t * 0 + 1, name="b", metadata={"current": 1.0})
    >>> s = ExperimentSet([a, b])
    >>> [e.name for e in s.filter(current=1.0)]
    ['b']
    """

    def __init__(self, experiments: Iterable[Experiment], name: str = "set") -> None:
        exps = tuple(experiments)
        seen: set[str] = set()
        for k, e in enumerate(exps):
            if not isinstance(e, Experiment):
                raise DataValidationError(
                    "experiments", f"item {k} is {type(e).__name__}, expected Experiment"
                )
            if e.name in seen:
                raise DataValidationError(
                    "name", f"duplicate record name {e.name!r} in set {name!r}"
                )
            seen.add(e.name)
        self._experiments = exps
        self.name = name

    # Sequence protocol ----------------------------------------------------------
    @overload
    def __getitem__(self, key: int) -> Experiment: ...
    @overload
    def __getitem__(self, key: slice) -> ExperimentSet: ...
    def __getitem__(self, key: int | slice | str) -> Any:  # type: ignore[override]
        if isinstance(key, str):
            for e in self._experiments:
                if e.name == key:
                    return e
            raise KeyError(f"no record named {key!r} in set {self.name!r}")
        if isinstance(key, slice):
            return ExperimentSet(self._experiments[key], name=self.name)
        return self._experiments[key]

    def __len__(self) -> int:
        return len(self._experiments)

    def __iter__(self) -> Iterator[Experiment]:
        return iter(self._experiments)

    def __repr__(self) -> str:
        return f"ExperimentSet(name={self.name!r}, n_records={len(self)})"

    @property
    def names(self) -> list[str]:
        """Record names in order."""
        return [e.name for e in self._experiments]

    # Selection ------------------------------------------------------------------
    def where(self, predicate: Callable[[Experiment], bool]) -> ExperimentSet:
        """Records for which ``predicate(experiment)`` is true."""
        return ExperimentSet([e for e in self if predicate(e)], name=self.name)

    def filter(self, **metadata: Any) -> ExperimentSet:
        """Records whose metadata match every ``key=value`` given.

        A value may be a collection (list, tuple, set) to accept any of its members. Floats
        compare with a relative tolerance of 1e-9.
        """

        def match(e: Experiment) -> bool:
            for k, want in metadata.items():
                if k not in e.metadata:
                    return False
                have = e.metadata[k]
                options = want if isinstance(want, (list, tuple, set, frozenset)) else (want,)
                if not any(metadata_equal(have, w) for w in options):
                    return False
            return True

        return self.where(match)

    def groups(self, key: str) -> dict[Any, ExperimentSet]:
        """Split by the value of metadata ``key`` (insertion order of first appearance)."""
        out: dict[Any, list[Experiment]] = {}
        for e in self:
            if key not in e.metadata:
                raise DataValidationError(key, f"record {e.name!r} has no metadata {key!r}")
            out.setdefault(e.metadata[key], []).append(e)
        return {k: ExperimentSet(v, name=f"{self.name}[{key}={k}]") for k, v in out.items()}

    def split(
        self, fractions: Sequence[float] = (0.7, 0.3), *, seed: int | None = None
    ) -> tuple[ExperimentSet, ...]:
        """Split whole records into consecutive parts (e.g. train / validation / test).

        Parameters
        ----------
        fractions : sequence of float
            Fractions of records per part; must sum to 1.
        seed : int, optional
            If given, records are shuffled with ``numpy.random.default_rng(seed)`` first;
            otherwise the order of the set is kept.
        """
        fr = np.asarray(fractions, dtype=float)
        if fr.ndim != 1 or np.any(fr < 0) or abs(fr.sum() - 1) > 1e-9:
            raise DataValidationError(
                "fractions", f"expected non-negative fractions summing to 1, got {fractions}"
            )
        order = np.arange(len(self))
        if seed is not None:
            order = np.random.default_rng(seed).permutation(len(self))
        cuts = np.round(np.cumsum(fr)[:-1] * len(self)).astype(int)
        return tuple(
            ExperimentSet([self._experiments[k] for k in part], name=self.name)
            for part in np.split(order, cuts)
        )

    def leave_one_group_out(self, key: str) -> Iterator[tuple[Any, ExperimentSet, ExperimentSet]]:
        """Yield ``(group, train, test)`` with each value of metadata ``key`` held out once."""
        groups = self.groups(key)
        for g, test in groups.items():
            train = ExperimentSet(
                [e for h, s in groups.items() if h != g for e in s], name=f"{self.name}[{key}!={g}]"
            )
            yield g, train, test

    # Summary ---------------------------------------------------------------------
    def to_frame(self) -> pd.DataFrame:
        """One row per record: name, samples, rate, duration and metadata."""
        rows = []
        for e in self:
            rows.append(
                {"name": e.name, "n": e.n, "fs": e.fs, "duration": e.duration, **e.metadata}
            )
        return pd.DataFrame(rows)


def metadata_equal(a: Any, b: Any) -> bool:
    """True when two metadata values match: numbers within a relative 1e-9, anything else by ``==``.

    The one rule by which :meth:`ExperimentSet.filter` and the study's record selections compare
    a record's metadata with a wanted value (so ``0.5`` matches ``0.5000000001``).

    Parameters
    ----------
    a, b : object
        Metadata values (numbers, strings, ...).

    Returns
    -------
    bool
    """
    if isinstance(a, (int, float, np.floating, np.integer)) and isinstance(
        b, (int, float, np.floating, np.integer)
    ):
        return bool(np.isclose(float(a), float(b), rtol=1e-9, atol=0.0))
    return bool(a == b)


def as_experiment_set(data: Experiment | Iterable[Experiment], name: str = "set") -> ExperimentSet:
    """Accept one Experiment, an iterable of them or an ExperimentSet; return an ExperimentSet.

    Parameters
    ----------
    data : Experiment or iterable of Experiment
        The record(s). An ExperimentSet is returned as is.
    name : str
        Name given to a newly built set.

    Returns
    -------
    ExperimentSet
    """
    if isinstance(data, ExperimentSet):
        return data
    if isinstance(data, Experiment):
        return ExperimentSet([data], name=data.name)
    return ExperimentSet(data, name=name)
