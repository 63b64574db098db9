"""hairfit: fit hair scattering models (Marschner 2003, Chiang 2016, ...) to fiber-scattering data.

Python bindings of the hairfit Rust library (the one implementation; the ``hairfit`` command
line calls the same functions). Arrays are NumPy float64; angles are in degrees unless
``angles="rad"``. Every keyword option is the command line's option of the same name
(``loss_scale=...`` is ``--loss-scale ...``), with the same defaults and checks; errors raise
:class:`HairfitError` with the message the command line prints after ``hairfit: error: ``.

Functions:

- :func:`eval` -- S at given angles, bit-identical to ``hairfit eval``.
- :func:`load` -- a data file's samples and the loader's report (``hairfit load``).
- :func:`data` -- samples from NumPy arrays, ready to fit.
- :func:`fit` -- fit a file, loaded data or arrays (``hairfit fit``): a :class:`FitResult`.
- :func:`synth` -- a synthetic dataset with its truth (``hairfit synth``).
- :func:`compare` -- fit several model families and rank them (``hairfit compare``).
- :func:`export` -- a renderer's material from a saved fit (``hairfit export``).
- :func:`families`, :func:`export_targets` -- what ``model=`` and ``to=`` take, with their facts.

Long calls (:func:`fit`, :func:`compare`) release the GIL and stop on Ctrl-C with
``KeyboardInterrupt``.
"""

from __future__ import annotations

import json
import os
import re
import warnings
from typing import Any, Callable, Dict, List, Mapping, Optional, Sequence, Tuple, Union

import numpy as np

from . import _native
from ._native import HairfitError

__version__: str = _native.__version__
try:  # tracebacks say hairfit.HairfitError, where users catch it
    HairfitError.__module__ = "hairfit"
except (AttributeError, TypeError):
    pass

__all__ = [
    "HairfitError",
    "Data",
    "FitResult",
    "eval",
    "eval_columns",
    "load",
    "data",
    "fit",
    "synth",
    "compare",
    "export",
    "families",
    "export_targets",
]

PathLike = Union[str, "os.PathLike[str]"]
Params = Union[Mapping[str, Any], PathLike]


# ----------------------------------------------------------------------------------------------
# Keyword arguments -> the command line's flags


def _flags(**options: Any) -> List[str]:
    """Command-line flags from keyword options: ``name=value`` is ``--name value``
    (underscores become dashes), ``True`` a bare flag, ``False``/``None`` nothing, a list or
    tuple the flag once per item, a mapping ``NAME=VALUE`` items (``fix={"eta": 1.55}``)."""
    out: List[str] = []
    for name, value in options.items():
        if value is None or value is False:
            continue
        flag = "--" + name.replace("_", "-")
        if value is True:
            out.append(flag)
            continue
        if isinstance(value, Mapping):
            items: Sequence[Any] = [f"{k}={_text(v)}" for k, v in value.items()]
        elif isinstance(value, (list, tuple)):
            items = value
        else:
            items = [value]
        for item in items:
            text = _text(item)
            # A value such as -1 goes as `--name=-1`, or the parser would read it as a flag.
            out.extend([f"{flag}={text}"] if text.startswith("-") else [flag, text])
    return out


def _text(value: Any) -> str:
    if isinstance(value, float):
        return repr(value)
    return os.fspath(value) if isinstance(value, os.PathLike) else str(value)


_LOAD_OPTIONS = (
    "format",
    "columns",
    "fixed",
    "map",
    "missing",
    "negative_tolerance",
    "delimiter",
)


def _split_load_options(options: Dict[str, Any]) -> Tuple[Dict[str, Any], Dict[str, Any]]:
    load_opts = {k: options.pop(k) for k in list(options) if k in _LOAD_OPTIONS}
    return load_opts, options


def _params_source(params: Params) -> Tuple[Optional[str], Optional[str]]:
    """(JSON text, path): a mapping as parameter-file JSON, else a params.json or a fit
    directory (the library reads its params.json, as `hairfit eval --params DIR` does)."""
    if isinstance(params, Mapping):
        return json.dumps({k: _param_value(k, v) for k, v in params.items()}), None
    return None, os.fspath(params)


def _param_value(key: str, value: Any) -> Any:
    """A params dict's value as JSON takes it: NumPy scalars and arrays become floats and lists;
    a NaN or infinity is refused with the key (JSON has no spelling for it)."""
    if isinstance(value, str) or value is None or isinstance(value, bool):
        return value
    if isinstance(value, np.ndarray) or isinstance(value, np.generic):
        if np.iscomplexobj(value):
            raise TypeError(f"params[{key!r}] is complex ({value!r}): pass a real number")
        value = value.tolist()
    if isinstance(value, (list, tuple)):
        return [_param_value(f"{key}[{i}]", v) for i, v in enumerate(value)]
    if isinstance(value, (int, float)) and not np.isfinite(value):
        raise HairfitError(
            f"params[{key!r}] is {value!r}: every parameter is a finite number "
            "(or a list of them, one per channel)"
        )
    return value


_UNEXPECTED = re.compile(r"unexpected argument '--([^'=]+)' found(?: \(tip: a similar argument exists: '--([^'=]+)'\))?")


def _keywords(func: str, call: Callable[[], Any]) -> Any:
    """Run `call`; a keyword argument the command line does not know (the parser's "unexpected
    argument '--modle'") is the TypeError Python gives for one, with the name meant."""
    try:
        return call()
    except HairfitError as e:
        m = _UNEXPECTED.search(str(e))
        if m is None:
            raise
        name = m.group(1).replace("-", "_")
        tip = f"; did you mean {m.group(2).replace('-', '_')!r}?" if m.group(2) else ""
        raise TypeError(f"{func}() got an unexpected keyword argument {name!r}{tip}") from None


def _model_flags(model: str, options: Dict[str, Any]) -> List[str]:
    return _flags(model=model, **options)


def _real(name: str, a: Any) -> Any:
    if np.iscomplexobj(a):
        raise TypeError(f"{name} is complex: hairfit takes real numbers (pass np.real({name}) if that is meant)")
    return a


def _angles_1d(name: str, a: Any) -> np.ndarray:
    arr = np.ascontiguousarray(_real(name, a), dtype=np.float64)
    if arr.ndim == 0:
        arr = arr.reshape(1)
    if arr.ndim != 1:
        raise HairfitError(f"{name} must be one-dimensional (got shape {arr.shape})")
    return arr


# ----------------------------------------------------------------------------------------------
# eval


def eval(  # noqa: A001 (the command's name)
    params: Params,
    theta_i: Any,
    phi_i: Any,
    theta_r: Any,
    phi_r: Any,
    model: str = "marschner",
    angles: str = "deg",
    out: Optional[np.ndarray] = None,
    **model_options: Any,
) -> np.ndarray:
    """S at every sample: an array (n, channels), float64.

    The values are bit for bit what ``hairfit eval --params P --input ANGLES.csv`` appends to
    the same angles (same kernel, same batches).

    Args:
        params: the parameters: a dict like a params.json (docs/model.md's names; with another
            ``model``, that family's page's, e.g. docs/chiang.md), or the path of a params.json
            or of a fit's directory (its params.json).
        theta_i, phi_i, theta_r, phi_r: the angles, 1-D arrays of one length (scalars are one
            sample), in ``angles`` units.
        model: ``"marschner"`` (default), ``"chiang"``, ``"kajiya-kay"``,
            ``"deon"``, ``"karis"`` or ``"frostbite"`` (docs/families.md).
        angles: ``"deg"`` (default) or ``"rad"``.
        out: an array to write S into and return instead of a new one (NumPy's ``out=``):
            float64, C-contiguous, shape (n, channels), writeable, sharing no memory with the
            angles. Re-using one across calls saves allocating and first touching the result's
            pages (a few percent of the time on millions of samples). After an error its
            contents are unspecified.
        **model_options: the command line's model options: ``mode="cubic"|"exact"``,
            ``lobes="R,TT,TRT"``, ``no_glints=True``, ``no_eccentricity=True`` (Marschner);
            ``terms="R,TT,TRT,residual"``, ``width_nodes="auto"|1024`` (Chiang); ``terms=...`` with
            the family's own term names (kajiya-kay, deon, karis, frostbite).

    Raises:
        HairfitError: bad parameters, options or angles (|θ| ≥ 90°, |φ| > 720°, not finite), or
            parameters the model cannot evaluate.
    """
    text, path = _params_source(params)
    arrays = [
        _angles_1d(n, a)
        for n, a in (("theta_i", theta_i), ("phi_i", phi_i), ("theta_r", theta_r), ("phi_r", phi_r))
    ]
    if out is not None and not (isinstance(out, np.ndarray) and out.dtype == np.float64
                                and out.ndim == 2):
        got = f"{type(out).__name__} {getattr(out, 'dtype', '')} {getattr(out, 'shape', '')}"
        raise HairfitError(f"out must be a 2-D float64 NumPy array (n, channels); got {got.strip()}")
    flags = _model_flags(model, model_options)
    n = len(arrays[0])
    if out is None and all(len(a) == n for a in arrays):
        # The result is allocated here, where NumPy turns a refused allocation into MemoryError
        # (allocated inside the extension, a refusal would surface as a Rust panic).
        nc = len(_keywords("eval", lambda: _native.eval_columns(text, path, flags)))
        try:
            out = np.empty((n, nc))
        except MemoryError as e:
            raise MemoryError(
                f"hairfit.eval: {e}: evaluate the samples in smaller chunks (passing out= to "
                "re-use one array), or raise the memory limit"
            ) from None
    return _keywords("eval", lambda: _native.eval(text, path, *arrays, flags, angles, out))


def eval_columns(params: Params, model: str = "marschner", **model_options: Any) -> List[str]:
    """The column names ``hairfit eval`` appends for these parameters: ``["s"]`` for a scalar
    ``sigma_a``, else ``["s_0", "s_1", ...]`` (one per channel of :func:`eval`'s result)."""
    text, path = _params_source(params)
    return _keywords("eval_columns", lambda: _native.eval_columns(text, path, _model_flags(model, model_options)))


# ----------------------------------------------------------------------------------------------
# Data


class Data:
    """Samples ready to fit: from a file (:func:`load`) or from arrays (:func:`data`).

    Attributes:
        theta_i, phi_i, theta_r, phi_r: angles in degrees (``angles_rad()`` gives radians),
            float64 arrays (n,).
        radiance: the values (n, channels).
        sigma, weight: (n, channels) or None.
        source_line: the 1-based line of each sample in its file (for arrays: the index + 1).
        channels: channel names (``["radiance"]`` or e.g. ``["r", "g", "b"]``).
        file: the file's path (None for arrays).
        report: the loader's report as a dict (``hairfit load --json``): ``rows_read``,
            ``accepted``, ``rejected`` (reason -> ``{"count", "first_lines"}``), ``warnings``...
        report_text: the report as ``hairfit load`` prints it.
    """

    def __init__(self, native: Any) -> None:
        self._native = native
        self.theta_i, self.phi_i, self.theta_r, self.phi_r = native.angles("deg")
        self.radiance: np.ndarray = native.radiance()
        self.sigma: Optional[np.ndarray] = native.sigma()
        self.weight: Optional[np.ndarray] = native.weight()
        self.source_line: np.ndarray = native.source_line()
        self.channels: List[str] = native.channels()
        self.file: Optional[str] = native.file()
        self.report: Dict[str, Any] = json.loads(native.report_json())
        self.report_text: str = native.report_text()

    def angles_rad(self) -> Tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(theta_i, phi_i, theta_r, phi_r) in radians, exactly as the fit uses them."""
        return tuple(self._native.angles("rad"))  # type: ignore[return-value]

    @property
    def rows_kept(self) -> int:
        """Rows the loader accepted (the samples)."""
        return int(self.report["accepted"])

    @property
    def rejected(self) -> Dict[str, Dict[str, Any]]:
        """Rejected rows by reason: ``{reason: {"count": n, "first_lines": [...]}}``."""
        return dict(self.report.get("rejected", {}))

    def __len__(self) -> int:
        return len(self._native)

    def __repr__(self) -> str:
        return (
            f"<hairfit.Data {len(self)} samples × {len(self.channels)} channels "
            f"({','.join(self.channels)}) from {self.file or '<arrays>'}>"
        )


def load(path: PathLike, angles: Optional[str] = None, **loader_options: Any) -> Data:
    """Load a data file as ``hairfit load PATH`` does: its samples and the report on every row.

    Args:
        path: a .csv with a header, a .json dataset, or a headerless scan (give ``columns``).
        angles: ``"deg"`` or ``"rad"``: the file's unit (default: degrees, or what a
            ``# angles:`` line says).
        **loader_options: ``format``, ``columns`` (list or "a,b,c"), ``fixed``
            (``{"theta_i": 20}`` or ``["theta_i=20"]``), ``map`` (``{"theta_r": "90-x"}``),
            ``missing``, ``negative_tolerance``, ``delimiter``: see data/README.md.

    Raises:
        HairfitError: the message ``hairfit load`` prints (file:line:column for malformed input).
    """
    flags = _load_flags(angles, loader_options)
    return Data(_keywords("load", lambda: _native.load(os.fspath(path), flags)))


def _load_flags(angles: Optional[str], options: Mapping[str, Any]) -> List[str]:
    opts = dict(options)
    for key in ("columns", "fixed"):
        if isinstance(opts.get(key), Mapping):
            opts[key] = [f"{k}={_text(v)}" for k, v in opts[key].items()]
    return _flags(angles=angles, **opts)


def data(
    theta_i: Any,
    phi_i: Any,
    theta_r: Any,
    phi_r: Any,
    radiance: Any,
    sigma: Any = None,
    weight: Any = None,
    channels: Optional[Sequence[str]] = None,
    angles: str = "deg",
) -> Data:
    """Samples from arrays, for :func:`fit`.

    Args:
        theta_i, phi_i, theta_r, phi_r: 1-D angle arrays (``angles`` units).
        radiance: (n,) or (n, channels) values.
        sigma, weight: optional, broadcast to radiance's shape; every value finite and > 0.
        channels: channel names (default ``["radiance"]`` for one channel, ``r, g, b`` for
            three, else ``c0, c1, ...``).
        angles: ``"deg"`` (default) or ``"rad"``.
    """
    arrays = [
        _angles_1d(n, a)
        for n, a in (("theta_i", theta_i), ("phi_i", phi_i), ("theta_r", theta_r), ("phi_r", phi_r))
    ]
    values = np.asarray(_real("radiance", radiance), dtype=np.float64)
    shape = values.shape
    if values.ndim == 1:
        values = values.reshape(-1, 1)
    if values.ndim != 2:
        raise HairfitError(f"radiance must be (n,) or (n, channels) (got shape {values.shape})")
    n = len(arrays[0])
    if values.shape[0] != n:
        hint = (
            f"; it looks transposed: pass radiance.T, shape ({n}, {values.shape[0]})"
            if values.shape[1] == n
            else ""
        )
        raise HairfitError(
            f"radiance has shape {shape} but there are {n} samples (theta_i has {n}): "
            f"one row per sample, (n,) or (n, channels){hint}"
        )
    values = np.ascontiguousarray(values)
    nc = values.shape[1]
    if channels is None:
        channels = ["radiance"] if nc == 1 else ["r", "g", "b"] if nc == 3 else [f"c{k}" for k in range(nc)]
    channels = [str(c) for c in channels]
    if len(channels) != nc:
        raise HairfitError(
            f"channels names {len(channels)} channel(s) {channels} but radiance has {nc} "
            f"(shape {shape}): one name per column of radiance"
        )
    twice = sorted({c for c in channels if channels.count(c) > 1})
    if twice:
        raise HairfitError(
            f"channel name {twice[0]!r} is given twice in channels {channels}: each channel "
            "needs its own name"
        )

    def table(x: Any) -> Optional[np.ndarray]:
        if x is None:
            return None
        return np.ascontiguousarray(np.broadcast_to(np.asarray(x, dtype=np.float64), values.shape))

    return Data(
        _native.data_from_arrays(
            *arrays, values, table(sigma), table(weight), list(channels), angles
        )
    )


_make_data = data  # `fit`'s argument `data` shadows the function


# ----------------------------------------------------------------------------------------------
# fit


class FitResult:
    """A finished fit: what ``hairfit fit`` writes into its --out directory, in memory.

    Attributes:
        params: the fitted parameters as a params.json dict (usable as :func:`eval`'s params).
        stderr: parameter name -> linearised standard error (None when fixed or undetermined).
        status: parameter name -> ``free``/``fixed``/``at_bound``/``undetermined``.
        intervals: parameter name -> ``{"68": (lo, hi), "95": (lo, hi)}`` profile-likelihood
            intervals (None sides are open; absent when not profiled).
        correlation: (names, matrix as a float array, NaN where undefined).
        scale: channel -> (value, standard error).
        verdict: ``good``, ``poor_fit``, ``undetermined``, ``failed`` or ``interrupted``.
        reasons: why, sentences with their numbers.
        chi2: Σ r² of the goodness-of-fit test (None when not computed).
        reduced_chi2: the residuals' reduced χ².
        warnings: the fit's warnings (the loader's first).
    """

    def __init__(self, native: Any) -> None:
        self._native = native
        self._json: Dict[str, Any] = json.loads(native.fit_json())
        j = self._json
        self.params: Dict[str, Any] = json.loads(native.params_json())
        self.stderr: Dict[str, Optional[float]] = {p["name"]: p["std_error"] for p in j["parameters"]}
        self.status: Dict[str, str] = {p["name"]: p["status"] for p in j["parameters"]}
        self.intervals: Dict[str, Dict[str, Tuple[Optional[float], Optional[float]]]] = {}
        for p in j["parameters"]:
            entry = {}
            for key, level in (("interval_68", "68"), ("interval_95", "95")):
                iv = p.get(key)
                if iv is not None:
                    entry[level] = (iv["lower"], iv["upper"])
            if entry:
                self.intervals[p["name"]] = entry
        corr = j.get("correlation", {})
        matrix = [[np.nan if v is None else v for v in row] for row in corr.get("matrix", [])]
        self.correlation: Tuple[List[str], np.ndarray] = (
            list(corr.get("names", [])),
            np.array(matrix, dtype=np.float64).reshape(len(matrix), len(matrix)),
        )
        self.scale: Dict[str, Tuple[Optional[float], Optional[float]]] = {
            s["channel"]: (s["value"], s["std_error"]) for s in j["scale"]
        }
        self.verdict: str = j["verdict"]
        self.reasons: List[str] = list(j.get("reasons", []))
        self.chi2: Optional[float] = j.get("goodness_of_fit", {}).get("chi2")
        self.reduced_chi2: Optional[float] = j["residuals"].get("reduced_chi2")
        self.warnings: List[str] = list(j.get("warnings", []))
        self.relative_misfit: float = native.relative_misfit()

    def to_dict(self) -> Dict[str, Any]:
        """fit.json's content (the same JSON ``hairfit fit`` writes, as a dict)."""
        return json.loads(self._native.fit_json())

    def timing(self) -> Dict[str, Any]:
        """timing.json's content: the run's wall-clock times."""
        return json.loads(self._native.timing_json())

    def summary(self) -> str:
        """The summary ``hairfit fit`` prints."""
        return self._native.summary()

    def save(self, dir: PathLike, force: bool = False) -> str:  # noqa: A002
        """Write exactly what ``hairfit fit --out DIR`` writes: fit.json, params.json,
        curves.csv, timing.json and the plotted report (index.html, SVG/PNG), published as one
        set (``force``: as ``--force``, replace a directory holding other files). Returns the
        report's line (``report: DIR/index.html``)."""
        return self._native.save(os.fspath(dir), force)

    def __repr__(self) -> str:
        return f"<hairfit.FitResult verdict={self.verdict} params={self.params}>"

    def __str__(self) -> str:
        return self.summary()


def fit(
    data: Union[PathLike, Data, Mapping[str, Any]],
    model: str = "marschner",
    fix: Optional[Union[Mapping[str, float], Sequence[str]]] = None,
    loss: str = "l2",
    angles: Optional[str] = None,
    progress: bool = False,
    **options: Any,
) -> FitResult:
    """Fit a model as ``hairfit fit DATA`` does (without --out: call :meth:`FitResult.save`).

    Args:
        data: a data file's path (loaded as :func:`load` does, with the loader options among
            ``options``), a :class:`Data`, or a dict of arrays for :func:`data`
            (``theta_i, phi_i, theta_r, phi_r, radiance``, optional ``sigma``, ``weight``,
            ``channels``).
        model: ``"marschner"`` (default), ``"chiang"``, ``"kajiya-kay"``,
            ``"deon"``, ``"karis"`` or ``"frostbite"`` (docs/families.md).
        fix: parameters to fix, ``{"eta": 1.55}`` or ``["eta=1.55"]`` (degrees for ``*_deg``).
        loss: ``l2``, ``huber``, ``cauchy`` or ``soft-l1``.
        angles: for a file, its unit (``deg``/``rad``); for a dict of arrays, theirs (default deg).
        progress: show the command line's progress bar on a terminal (off by default).
        **options: every other ``hairfit fit`` option by its name: ``space``, ``loss_scale``,
            ``intervals``, ``starts``, ``seed``, ``global_`` (``--global``), ``free``,
            ``effects``, ``subsample``, ``polish``, ``start_iters``, ``polish_iters``,
            ``curves``, ``strict``, ``measurement``, ``mode``, ``lobes``, ``no_glints``,
            ``no_eccentricity``, ``terms``, ``width_nodes``; and for a file the loader's
            (``format``, ``columns``, ``fixed``, ``map``, ``missing``, ...).

    Raises:
        HairfitError: what ``hairfit fit`` reports for the same input and options.
        KeyboardInterrupt: Ctrl-C during the fit (the fit stops at its next iteration).
    """
    options = dict(options)
    if "global_" in options:
        options["global"] = options.pop("global_")
    load_opts, fit_opts = _split_load_options(options)
    fit_flags = _flags(model=model, fix=fix, loss=loss, no_progress=not progress, **fit_opts)
    if isinstance(data, Data):
        if load_opts or angles is not None:
            raise HairfitError("loader options apply to a file: pass them to hairfit.load")
        return FitResult(_keywords("fit", lambda: _native.fit(data._native, fit_flags)))
    if isinstance(data, Mapping):
        if load_opts:
            raise HairfitError("loader options apply to a file, not to arrays")
        arrays = dict(data)
        d = _make_data(angles=angles or "deg", **arrays)
        return FitResult(_keywords("fit", lambda: _native.fit(d._native, fit_flags)))
    path = os.fspath(data)
    return FitResult(
        _keywords("fit", lambda: _native.fit_file(path, _load_flags(angles, load_opts), fit_flags))
    )


# ----------------------------------------------------------------------------------------------
# synth, compare, export


def synth(
    params: PathLike,
    rig: str,
    output: PathLike,
    **options: Any,
) -> Dict[str, Any]:
    """Synthesize a dataset as ``hairfit synth --params P --rig RIG --output F.csv`` does.

    Args:
        params: the true parameters' file (params.json).
        rig: the rig (``hairfit synth --help`` lists them).
        output: the CSV to write (``F.csv``; the truth goes to ``F.truth.json``).
        **options: ``noise``, ``seed``, ``outlier_kind``, ``outlier_range`` (``"LO..HI"``),
            ``channels``, ``scale`` (list), ``measurement``, ``max_memory``, and the model
            options (``model``, ``mode``, ...).

    Returns:
        ``{"csv", "truth", "n_samples", "n_outliers", "notes"}``.
    """
    if isinstance(params, Mapping):
        raise HairfitError("synth reads its parameters from a file: pass a params.json path")
    flags = _flags(params=params, rig=rig, output=output, **options)
    csv, truth, n, n_out, notes = _keywords("synth", lambda: _native.synth(flags))
    return {"csv": csv, "truth": truth, "n_samples": n, "n_outliers": n_out, "notes": notes}


def compare(
    data: PathLike,
    out: PathLike,
    progress: bool = False,
    models: Union[str, Sequence[str], None] = None,
    **options: Any,
) -> Dict[str, Any]:
    """Fit several model families to the same data and rank them, as
    ``hairfit compare DATA --models A,B --out DIR``.

    Args:
        models: the families, ``"marschner,chiang"`` (the default when None), a list of
            names, or ``"all"``.

    Writes DIR/<family>/ per family, DIR/compare.json and DIR/index.html. Returns
    compare.json's content (``models``, ``ranking`` best first, ``regions``, ``findings``) with
    the printed summary under ``"summary_text"``. ``options`` are ``hairfit compare``'s (the
    fit's and the loader's, e.g. ``fix``, ``loss``, ``force``, ``terms``).
    """
    options = dict(options)
    if "global_" in options:
        options["global"] = options.pop("global_")
    if models is not None and not isinstance(models, str):
        models = ",".join(models)
    flags = [os.fspath(data)] + _flags(out=out, no_progress=not progress, models=models, **options)
    text = _keywords("compare", lambda: _native.compare(flags))
    result: Dict[str, Any] = {}
    path = os.path.join(os.fspath(out), "compare.json")
    if os.path.exists(path):
        with open(path, encoding="utf-8") as f:
            result = json.load(f)
    result["summary_text"] = text
    return result


def export(
    fit_dir: PathLike, to: str, output: Optional[PathLike] = None, allow_failed: bool = False
) -> str:
    """What a renderer loads from a saved fit, as ``hairfit export DIR --to R [--output F]``.

    Args:
        fit_dir: a fit's directory (:meth:`FitResult.save` or ``hairfit fit --out``).
        to: ``pbrt``, ``blender``, ``materialx`` (the renderer's Chiang variant), ``unreal``
            (Unreal Engine 5 hair material inputs as JSON; with ``output``, its editor Python
            script beside it) or ``unity`` (Unity HDRP hair inputs: ``output`` is required and
            names the JSON; the C# editor script goes beside it).
        output: a file to write (atomically); when None the text is returned.
        allow_failed: export a fit whose verdict is ``failed`` (refused otherwise: its
            parameters are not a fit); the summary warns that they are not (without
            ``output``, a Python warning does).

    Returns:
        The file's text when ``output`` is None, else the command's summary line (the mapping's
        error and where it wrote).
    """
    summary, text = _native.export([os.fspath(fit_dir)] + _flags(to=to, output=output, allow_failed=allow_failed))
    if text is None:
        return summary
    # The summary is not returned with the text: its warnings (a failed fit exported with
    # allow_failed, an interrupted fit) go to Python's warnings instead of being lost.
    for line in summary.splitlines():
        if line.startswith("warning: "):
            warnings.warn(line[len("warning: "):], stacklevel=2)
    return text


def families() -> List[Dict[str, Any]]:
    """Every model family ``model=`` takes, in the order ``compare(models="all")`` ranks them (the
    first is the default), from the registry the command line's help is written from.

    Returns:
        One dict per family: ``name`` (the ``model=`` word), ``title``, ``citation``,
        ``parameters`` (the names its parameter files use) and ``terms`` (the words ``terms=``
        switches, or None when it takes no ``terms=``).
    """
    return [
        {"name": name, "title": title, "citation": citation, "parameters": parameters, "terms": terms}
        for name, title, citation, parameters, terms in _native.families()
    ]


def export_targets() -> List[Dict[str, str]]:
    """Every target ``export(to=...)`` takes, in ``hairfit export --to``'s order.

    Returns:
        One dict per target: ``name`` (the ``to=`` word), ``program`` (what loads the file),
        ``extension`` (of the main file written, without the dot) and ``file_kind``.
    """
    return [
        {"name": name, "program": program, "extension": extension, "file_kind": kind}
        for name, program, extension, kind in _native.export_targets()
    ]
