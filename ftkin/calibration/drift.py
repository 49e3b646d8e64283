"""A sensor bias that drifts with time: the trajectory, the drift-model protocol and its registry.

Strain-gauge sensors drift (warm-up after power-on, temperature): when the
samples carry reading times, :func:`~ftkin.calibration.calibrate` can model the
bias ``b(t) = [F0(t), M0(t)]`` [N, N·m, sensor frame] as a function of time while the
tool weight ``a`` and centre of mass ``P`` stay constant. Every drift model has the form

    b(t) = b(T) + basis((t − T) / span) · c  (+ a random walk pinned at ``T``)

with ``T`` the last pose time, ``basis`` ``K`` functions of the scaled time that vanish
at 0 and ``c`` ``(K, 6)`` coefficients. A model is a :class:`DriftModel` (the
protocol: fit, bias at ``t``, information for planning, serialisation), registered
by name with :func:`register_drift_model`; a drift spec names one, or a sum of them
joined by ``+``, or ``"auto"``. The built-in models:

* ``"none"``: a constant bias (the static model of METHOD.md §3; this module);
* ``"poly:N"``: a polynomial of degree ``N`` (``1 ≤ N ≤ 5``, :mod:`ftkin.calibration.drift_poly`);
* ``"random-walk"``: ``b(t) − b(s) ~ N(0, q² |t − s|)`` per channel with a rate ``q``
  [N/√s] shared by the forces and one [N·m/√s] by the torques
  (:mod:`ftkin.calibration.drift_walk`; its filter in :mod:`ftkin.calibration.random_walk`);
* ``"random-walk+poly:N"``: a random walk around a polynomial trend (a warm-up plus wandering);
* ``"auto"``: the candidate with the lowest Bayesian information criterion among the
  registered ``auto`` candidates (:mod:`ftkin.calibration.drift_fit`).

In every model the bias reported as ``force_offset``/``torque_offset`` is the
bias at the end of the recording ``T``: the one to use when compensating
afterwards. :class:`BiasDrift` carries the whole trajectory.
"""

from collections.abc import Callable
from dataclasses import dataclass, field
from numbers import Real

import numpy as np

from ..exceptions import InvalidInput
from ..validation import as_float_array


def trend_columns(basis: np.ndarray) -> np.ndarray:
    """``(P, 6, 6K)`` Jacobian of the bias trend ``basis · c`` ``(P, 6)`` with respect to ``c``
    flattened row by row (``c[k, d]`` is column ``6k + d``).
    """
    return np.einsum("pk,cd->pckd", basis, np.eye(6)).reshape(len(basis), 6, -1)


@dataclass(frozen=True)
class DriftModel:
    """A drift model: ``K`` basis functions of the scaled time, and whether a random walk is added.

    The base class is the constant bias (``"none"``: no basis, no walk). A new
    model subclasses it (at least :meth:`basis` and :attr:`columns`) and registers a
    factory with :func:`register_drift_model`; fitting, the bias at any time,
    the planning information and the calibration file then work for it unchanged.
    A model whose basis has parameters of its own can override :meth:`fit`.

    Attributes:
        name: The spec that names this model (``"poly:2"``).
        columns: Number ``K`` of basis functions (rows of six coefficients).
        walk: True when a random walk (rates estimated) is part of the bias.
    """

    name: str = "none"
    columns: int = 0
    walk: bool = False

    def basis(self, tau: np.ndarray) -> np.ndarray:
        """``(N, K)`` basis functions at scaled times ``tau = (t − T) / span`` ``(N,)`` (0 at
        ``T``).
        """
        return np.zeros((len(tau), 0))

    def fit(self, poses, start, selected_by: str = "given"):
        """A fit of its own, for a model whose basis has parameters of its own: a
        :class:`~ftkin.calibration.drift_fit.DriftFit` of ``θ`` and this drift from a
        constant-bias start. The base returns None: the generic Gauss–Newton fit
        (:func:`~ftkin.calibration.drift_fit.fit_drift_model`) then serves the model (the fit
        imports the models; a model never imports the fit).
        """
        return None

    def bias_at(self, drift: "BiasDrift", times: np.ndarray) -> np.ndarray:
        """``(N, 6)`` bias [N, N·m] at ``times`` ``(N,)`` [s] inside the pose times.

        With a walk, the smoothed bias linear between pose times (the exact
        conditional mean of a random walk); otherwise the trend.
        """
        if self.walk:
            return np.column_stack([np.interp(times, drift.times, b) for b in drift.bias.T])
        if not self.columns:
            return drift.end_bias
        return (
            drift.end_bias
            + self.basis((times - drift.end_time) / drift.time_scale) @ drift.coefficients
        )

    def information(self, jacobians, times, noise_variance, rate=None) -> np.ndarray:
        """Fisher information ``(..., 12, 12)`` of ``θ`` with the drift marginalized, for poses
        visited at ``times`` ``(P,)`` [s] (planning).

        ``jacobians`` ``(..., P, 6, 12)`` of the prediction (leading axes:
        candidate pose orders), ``noise_variance`` ``(P, 6)`` of the pose means
        [N², N²·m²], ``rate`` ``(6,)`` of the walk [N/√s, N·m/√s] (with a walk).
        """
        from .random_walk import walk_gains, whiten

        times = np.asarray(times, dtype=float)
        tau = (times - times[-1]) / max(float(times[-1] - times[0]), 1e-300)
        trend = np.broadcast_to(
            trend_columns(self.basis(tau)), jacobians.shape[:-1] + (6 * self.columns,)
        )
        rate = np.zeros(6) if rate is None or not self.walk else np.asarray(rate, dtype=float)
        white = whiten(
            walk_gains(times, noise_variance, rate), np.concatenate([jacobians, trend], -1)
        )
        full = np.einsum("...pki,...pkj->...ij", white, white)
        if not self.columns:
            return full
        return full[..., :12, :12] - full[..., :12, 12:] @ np.linalg.solve(
            full[..., 12:, 12:], full[..., 12:, :12]
        )

    def to_document(self, drift: "BiasDrift") -> dict:
        """This model's entries of the calibration file's ``drift`` object."""
        return {"rate": drift.rate, "coefficients": drift.coefficients}

    def from_document(self, reader) -> dict:
        """This model's :class:`BiasDrift` arguments from the file's ``drift`` object (a
        :class:`~ftkin.io.json_reader.NestedReader`).
        """
        return {
            "rate": reader.array("rate", (2,), required=False),
            "coefficients": reader.array("coefficients", (self.columns, 6), required=False),
        }


@dataclass(frozen=True)
class DriftSum(DriftModel):
    """The sum of drift models (``"random-walk+poly:2"``): their bases side by side, at most one
    walk.
    """

    parts: tuple[DriftModel, ...] = ()

    def basis(self, tau: np.ndarray) -> np.ndarray:
        return np.concatenate([part.basis(tau) for part in self.parts], axis=1)


@dataclass(frozen=True)
class DriftEntry:
    """A registered drift model.

    Attributes:
        name: The name in a drift spec (``"poly"``).
        make: ``make(argument)`` returns the :class:`DriftModel` for ``name:argument`` (argument
            None without a colon); it raises :class:`~ftkin.exceptions.InvalidInput` for a bad one.
        usage: How a spec writes it (``"poly:N"``).
        auto: Specs ``drift="auto"`` compares because of this entry.
        walk: True when the model is a random walk (it may then carry another model's trend).
    """

    name: str
    make: Callable[[str | None], DriftModel]
    usage: str
    auto: tuple[str, ...] = ()
    walk: bool = False


DRIFT_MODELS: dict[str, DriftEntry] = {}
"""The registry: drift models by name (:func:`register_drift_model`)."""


def register_drift_model(
    name: str,
    make: Callable,
    *,
    usage: str | None = None,
    auto: tuple[str, ...] = (),
    walk: bool = False,
) -> DriftEntry:
    """Register a drift model under ``name`` (see :class:`DriftEntry`); returns the entry.

    Raises:
        InvalidInput: a name that is taken, ``"auto"``, or not a plain word.
    """
    if name in DRIFT_MODELS or name == "auto" or not name.replace("-", "").isalnum():
        raise InvalidInput(f"cannot register a drift model named {name!r} (taken or not a word)")
    DRIFT_MODELS[name] = DriftEntry(name, make, usage or name, tuple(auto), walk)
    return DRIFT_MODELS[name]


def drift_choices() -> tuple[str, ...]:
    """The drift specs :func:`~ftkin.calibration.calibrate` accepts now (``N`` a number)."""
    _load_built_in()
    entries = DRIFT_MODELS.values()
    trends = [entry.usage for entry in entries if not entry.walk and entry.name != "none"]
    sums = [f"{entry.usage}+{trend}" for entry in entries if entry.walk for trend in trends]
    return ("auto", *(entry.usage for entry in entries), *sums)


def auto_candidates() -> tuple[str, ...]:
    """The specs ``drift="auto"`` compares, ``"none"`` first."""
    _load_built_in()
    return ("none", *(spec for entry in DRIFT_MODELS.values() for spec in entry.auto))


def parse_drift(spec) -> DriftModel:
    """The :class:`DriftModel` a spec names (``"none"``, ``"poly:2"``, ``"random-walk+poly:1"``,
    any registered name; not ``"auto"``).

    Raises:
        InvalidInput: not a string, an unknown name, a bad argument, ``none`` or
            a model twice in a sum, or two walks.
    """
    if not isinstance(spec, str) or spec == "auto":
        raise InvalidInput(
            f"unknown drift model {spec!r}; a fitted model is one of "
            f"{', '.join(drift_choices()[1:])}"
        )
    parts = []
    for text in spec.split("+"):
        name, colon, argument = text.partition(":")
        if name not in DRIFT_MODELS and name in BUILT_IN_MODELS:
            _load_built_in()
        if name not in DRIFT_MODELS:
            raise InvalidInput(
                f"unknown drift model {spec!r}; expected one of {', '.join(drift_choices())}"
            )
        parts.append(DRIFT_MODELS[name].make(argument if colon else None))
    if len(parts) == 1:
        return parts[0]
    names = [part.name.partition(":")[0] for part in parts]
    if "none" in names or len(set(names)) < len(names) or sum(p.walk for p in parts) > 1:
        raise InvalidInput(f"drift {spec!r}: a sum of distinct models with at most one walk")
    return DriftSum(
        "+".join(part.name for part in parts),  # canonical: poly:02 is poly:2
        sum(part.columns for part in parts),
        any(part.walk for part in parts),
        tuple(parts),
    )


def drift_candidates(spec) -> tuple[DriftModel, ...]:
    """The models a ``drift=`` value asks to fit: all :func:`auto_candidates` for ``"auto"``,
    else the one it names.
    """
    return tuple(map(parse_drift, auto_candidates() if spec == "auto" else (spec,)))


def _check_array(value, name: str, shape: tuple, positive: bool = False) -> np.ndarray | None:
    if value is None:
        return None
    value = as_float_array(value, name).copy()  # frozen below: never the caller's array
    if value.shape != shape or not np.all(np.isfinite(value)) or (positive and np.any(value < 0)):
        raise InvalidInput(
            f"drift {name} must be finite {'≥ 0 ' if positive else ''}with shape {shape}, got "
            f"{value.shape}" + (f" {value.tolist()}" if value.size < 8 else "")
        )
    value.setflags(write=False)
    return value


@dataclass(frozen=True)
class BiasDrift:
    """The bias trajectory a drift-aware calibration found.

    Attributes:
        model: The fitted model's spec (``"none"``, ``"poly:N"``, ``"random-walk"``, ...).
        selected_by: ``"auto"`` (chosen by the information criterion) or ``"given"``.
        times: ``(P,)`` pose times, ascending [s] (mean time of each pose's readings).
        bias: ``(P, 6)`` bias ``[F0, M0]`` at those times [N, N·m, sensor frame].
        bias_std: ``(P, 6)`` its standard deviation (the drift model's
            uncertainty at each time plus that of the end bias) [N, N·m].
        rate: ``(2,)`` random-walk rate [N/√s, N·m/√s] (a model with a walk), else None.
        coefficients: ``(K, 6)`` coefficients ``c`` [N, N·m] of the model's basis
            of ``(t − T) / time_scale`` (a model with a basis), else None.
        time_scale: ``span`` of the basis's time variable [s] (the recording's length).
        criteria: BIC of each candidate model ``auto`` compared (empty otherwise).
        recorded_span: ``(2,)`` first and last reading time of the recording [s]
            (the pose times are means, inside it), or None (the pose times' span).
    """

    model: str
    selected_by: str
    times: np.ndarray
    bias: np.ndarray
    bias_std: np.ndarray
    rate: np.ndarray | None = None
    coefficients: np.ndarray | None = None
    time_scale: float = 1.0
    criteria: dict = field(default_factory=dict)
    recorded_span: np.ndarray | None = None
    kind: DriftModel = field(init=False, repr=False, compare=False)

    def __post_init__(self):
        object.__setattr__(self, "kind", parse_drift(self.model))
        times = as_float_array(self.times, "times").reshape(-1)
        for refused, message in (
            (
                self.selected_by not in ("auto", "given"),
                f"selected_by must be 'auto' or 'given', got {self.selected_by!r}",
            ),
            (
                not (isinstance(self.time_scale, Real) and 0 < self.time_scale < np.inf),
                f"time_scale must be a finite time > 0 [s], got {self.time_scale!r}",
            ),
            (
                len(times) == 0 or np.any(np.diff(times) < 0) or not np.all(np.isfinite(times)),
                "drift times must be finite, ascending and not empty [s]",
            ),
        ):
            if refused:
                raise InvalidInput(message)
        rows = None if self.coefficients is None else self.kind.columns  # the check names others
        for name, shape, positive in (
            ("times", times.shape, False),
            ("bias", (len(times), 6), False),
            ("bias_std", (len(times), 6), False),
            ("rate", (2,), True),
            ("coefficients", (rows, 6), False),
            ("recorded_span", (2,), False),
        ):
            object.__setattr__(self, name, _check_array(getattr(self, name), name, shape, positive))
        span, kind = self.recorded_span, self.kind
        if span is not None and span[0] > span[1]:
            raise InvalidInput(f"recorded_span must be [first, last] [s], got {span}")
        if (self.rate is not None) != kind.walk or (rows or 0) != kind.columns:
            raise InvalidInput(
                f"drift {self.model!r} has {kind.columns} coefficient rows and "
                f"{'a' if kind.walk else 'no'} rate, got {rows or 0} and "
                f"{'a' if self.rate is not None else 'no'} rate"
            )

    @property
    def start_time(self) -> float:
        """First pose time [s]."""
        return float(self.times[0])

    @property
    def end_time(self) -> float:
        """Last pose time ``T`` [s]: the bias there is the calibration's
        ``force_offset``/``torque_offset``.
        """
        return float(self.times[-1])

    def covers(self, times) -> np.ndarray:
        """``(N,)`` True where ``times`` [s] fall inside the recording (:attr:`recorded_span`, else
        the pose times).
        """
        span = self.recorded_span if self.recorded_span is not None else self.times[[0, -1]]
        times = as_float_array(times, "times").reshape(-1)
        return (times >= span[0]) & (times <= span[1])

    @property
    def end_bias(self) -> np.ndarray:
        """``(6,)`` bias at the end of the recording [N, N·m]."""
        return self.bias[-1]

    @property
    def drift_range(self) -> np.ndarray:
        """``(6,)`` largest minus smallest bias over the recording [N, N·m]."""
        return np.ptp(self.bias, axis=0)

    def bias_at(self, times) -> np.ndarray:
        """Bias ``(N, 6)`` [N, N·m] at ``times`` ``(N,)`` [s] (``(6,)`` for a scalar).

        Inside the pose times the model's (:meth:`DriftModel.bias_at`); outside
        held at the first or last value (no extrapolation).
        """
        times = as_float_array(times, "times")
        clipped = np.clip(times.reshape(-1), self.times[0], self.times[-1])
        out = np.broadcast_to(self.kind.bias_at(self, clipped), (len(clipped), 6)).copy()
        return out[0] if times.ndim == 0 else out

    def describe(self) -> str:
        """One line: model, how it was chosen, range of the bias over the recording."""
        force_range, torque_range = self.drift_range[:3].max(), self.drift_range[3:].max()
        text = (
            f"{self.model} ({'chosen by BIC' if self.selected_by == 'auto' else 'given'}) over "
            f"{self.end_time - self.start_time:.4g} s; bias range up to {force_range:.4f} N, "
            f"{torque_range:.5f} N·m"
        )
        if self.rate is not None:
            text += f"; rate {self.rate[0]:.3g} N/√s, {self.rate[1]:.3g} N·m/√s"
        return text


def without_argument(model: DriftModel) -> Callable[[str | None], DriftModel]:
    """The factory of a model that takes no argument (``"none"``, ``"random-walk"``)."""

    def make(argument: str | None) -> DriftModel:
        if argument is not None:
            raise InvalidInput(
                f"drift '{model.name}' takes no argument, got '{model.name}:{argument}'"
            )
        return model

    return make


register_drift_model("none", without_argument(DriftModel()))

BUILT_IN_MODELS = {"poly": ".drift_poly", "random-walk": ".drift_walk"}
"""The built-in models' names → their modules, which register them when they load: a model's
module is imported when a spec, ``auto`` or a listing first needs the registry, never by a
calibration without times (:func:`check_drift_spec`)."""


def _load_built_in() -> None:
    import importlib

    for module in BUILT_IN_MODELS.values():
        importlib.import_module(module, __package__)


def check_drift_spec(spec) -> str:
    """``spec`` if it names a drift the calibration can fit, else :class:`InvalidInput` (the one
    check of a ``drift=`` value). ``"auto"`` and ``"none"`` are accepted without importing or
    building any model; another spec is parsed (importing the model it names).
    """
    if spec in ("auto", "none"):
        return spec
    parse_drift(spec)
    return spec


def __getattr__(name: str):
    if name == "DRIFT_CHOICES":  # the drift= values with the built-in models (loads them)
        return drift_choices()
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
