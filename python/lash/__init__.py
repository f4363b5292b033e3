"""Lash from Python: planar mechanisms with clearance joints.

    import lash
    model = lash.load("examples/flores_slider_crank.yaml")
    model.set("joints.rod_slider.clearance", 0.25e-3)
    result = lash.simulate(model, t_end=0.024)
    result["slider.ax"]         # NumPy array (a view into the run's output, no copy)
    result.events               # dict of arrays: time, joint, event, velocity
    result.summary              # dict: status, channels (peaks), clearance_joints, integrator
    result.to_pandas()          # a DataFrame, when pandas is installed
    lash.analysis.analyze(model)                 # verdict, Poincare sections, spectra, ...

Models are model files (docs/model-format.md): `Model` keeps the file's text and the list of
overrides (the CLI's `--set KEY.PATH=VALUE`), and the C++ loader validates them whenever the
model is used, so every error reads as the CLI's, `file:line:column: ...`, raised as
`lash.ModelError`. Models can also be built in code (`Model.new`, `add_body`, `add_joint`,
`add_clearance_joint`, `add_driver`, ...) and saved with `Model.save`.
"""
from __future__ import annotations

import json
import math
import numbers
import operator
import os
import re
from collections.abc import Mapping
from typing import Any, Dict, Iterable, List, Optional, Sequence

import numpy as np

from . import _lash
from ._lash import IoError, ModelError

ModelError.__module__ = IoError.__module__ = "lash"
ModelError.__doc__ = """A bad model file or override (a ValueError), raised by load, Model.check and
simulate. str() lists every problem as the CLI does, `file:line:column: element: message`
(line 0 for an override); `.diagnostics` holds them as (file, line, column, element, message)."""
IoError.__doc__ = """A file Lash could not read or write (an OSError), with the path and the reason."""

__all__ = ["Model", "Result", "Study", "ModelError", "IoError", "load", "loads", "simulate",
           "sweep", "read_study", "analysis"]
__version__ = "0.1.0"


def _yaml_value(value: Any) -> str:
    """A Python value as the text of an override value (shortest round-trip for floats)."""
    if isinstance(value, (bool, np.bool_)):
        return "true" if value else "false"
    if isinstance(value, (int, float, np.floating, np.integer)):
        if isinstance(value, (float, np.floating)):
            return repr(_real("value", value))
        return str(int(value))
    if isinstance(value, str):
        return value
    if isinstance(value, (list, tuple, dict, np.ndarray)):
        return _flow_yaml(value)
    raise TypeError(f"cannot set a {type(value).__name__} as a model value")


def _plain(value: Any) -> Any:
    """`value` with NumPy arrays and scalars (anything with `tolist`) as Python lists and
    numbers, through dicts, lists and tuples: the data a model file holds."""
    if isinstance(value, dict):
        for k in value:  # a model file's keys are names: None or (1, 2) was written as "~" or "[1, 2]"
            if not isinstance(k, str):
                raise TypeError(f"a model's keys are names (str), got {_short(k)} "
                                f"({type(k).__name__}) as a key")
        return {k: _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if isinstance(value, np.floating) and value.dtype.itemsize < 8:
        return _real("value", value)  # np.float32(0.3) is 0.3, as _real takes it
    if isinstance(value, np.ndarray):
        if value.ndim == 0:  # np.array(1.0): its scalar
            return _plain(value[()])
        return [_plain(v) for v in value]  # element by element: narrow floats as above
    if not isinstance(value, (str, bytes)) and hasattr(value, "tolist"):
        return _plain(value.tolist())
    return value


def _flow_yaml(value: Any) -> str:
    """A list or map as one line of YAML flow style, as an override's value must be (a block-style
    map spans lines, and the override reader took its text for a string). Strings inside are
    quoted (JSON's quoting is YAML's)."""
    if isinstance(value, dict):
        return "{" + ", ".join(f"{json.dumps(str(k))}: {_flow_yaml(v)}" for k, v in value.items()) + "}"
    if isinstance(value, (list, tuple, np.ndarray)):
        return "[" + ", ".join(_flow_yaml(v) for v in value) + "]"
    if isinstance(value, str):
        return json.dumps(value)
    return _yaml_value(value)


def _override_list(overrides: str | Iterable[str]) -> List[str]:
    """`overrides` as a list of "KEY.PATH=VALUE" strings: a single string is one override (not
    its characters); anything else must be an iterable of strings."""
    return _strings("overrides", overrides, "\"KEY.PATH=VALUE\" strings")


def _short(value: Any) -> str:
    """repr(value) cut to a line, for messages (an array or a model text is not repeated whole)."""
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


def _real(name: str, value: Any, what: str = "a number") -> float:
    """`value` as a float: any real number (int, float, NumPy's integers and floats), not a bool;
    TypeError naming the argument `name` otherwise. A NumPy float narrower than a double
    (np.float32(0.002)) is the decimal it prints as (0.002), not its binary value widened
    (0.0020000000949949026)."""
    if isinstance(value, np.ndarray) and value.ndim == 0:  # np.array(1.0): its scalar
        value = value[()]
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Real):
        raise TypeError(f"{name}: expected {what}, got {_short(value)} ({type(value).__name__})")
    if isinstance(value, np.floating) and value.dtype.itemsize < 8:
        return float(str(value))
    try:
        return float(value)
    except OverflowError:  # an int beyond the largest double
        raise ValueError(f"{name}: {_short(value)} is beyond the largest number a double holds "
                         f"(about 1.8e308)") from None


def _integer(name: str, value: Any, what: str = "a whole number") -> int:
    """`value` as an int: an int or NumPy integer (operator.index), not a bool or a float;
    TypeError naming the argument `name` otherwise."""
    if not isinstance(value, (bool, np.bool_)):
        try:
            return operator.index(value)
        except TypeError:
            pass
    raise TypeError(f"{name}: expected {what}, got {_short(value)} ({type(value).__name__})")


def _flag(name: str, value: Any) -> bool:
    """`value` as a bool: True or False (or NumPy's); TypeError naming `name` otherwise."""
    if not isinstance(value, (bool, np.bool_)):
        raise TypeError(f"{name}: expected True or False, got {_short(value)} "
                        f"({type(value).__name__})")
    return bool(value)


def _string(name: str, value: Any, what: str) -> str:
    """`value`, a str; TypeError naming `name` and `what` was expected otherwise."""
    if not isinstance(value, str):
        raise TypeError(f"{name}: expected {what}, got {_short(value)} ({type(value).__name__})")
    return value


def _strings(name: str, value: Any, what: str) -> List[str]:
    """`value` as a list of str: a single str is one item (not its characters), anything else an
    iterable of str; TypeError naming `name` and `what` each item is otherwise."""
    if isinstance(value, str):
        return [value]
    try:
        items = list(value)
    except TypeError:
        raise TypeError(f"{name}: expected a list of {what}, got {_short(value)} "
                        f"({type(value).__name__})") from None
    for item in items:
        if not isinstance(item, str):
            raise TypeError(f"{name}: expected {what}, got {_short(item)} ({type(item).__name__})")
    return items


def _point(name: str, value: Any) -> List[Any]:
    """`value` as a point [x, y] (m): two real numbers; TypeError naming `name` otherwise."""
    if isinstance(value, (str, bytes)) or not isinstance(value, (Sequence, np.ndarray)) \
            or np.ndim(value) != 1 or len(value) != 2:
        raise TypeError(f"{name}: expected a point [x, y] (m), got {_short(value)} "
                        f"({type(value).__name__})")
    return [_real(f"{name}: x" if i == 0 else f"{name}: y", v) for i, v in enumerate(value)]


def _message_name(filename: str) -> str:
    """`filename` as UTF-8 text for messages: a name that is not UTF-8 (bytes that os.fsdecode
    kept as surrogate escapes) shows those bytes as \\xNN, as `lash check` prints them raw."""
    try:
        return os.fsencode(filename).decode("utf-8", "backslashreplace")
    except UnicodeEncodeError:  # a lone surrogate that no file name's bytes make
        return filename.encode("utf-8", "backslashreplace").decode("utf-8")


def _update(section: dict, spec: Dict[str, Any]) -> None:
    """`section` updated with `spec`; a value None removes its key (an empty value in a model
    file is an error, not the default)."""
    for key, value in spec.items():
        if value is None:
            section.pop(key, None)
        else:
            section[key] = value


# Singular of each model section holding named elements, for messages.
_ELEMENT_KIND = {"bodies": "body", "joints": "joint", "drivers": "driver", "loads": "load",
                 "sensors": "sensor"}


class Model:
    """A mechanism: a model file's text (or data built in code) plus overrides.

    Nothing is validated until the model is used (`check`, `simulate`, `channels`, ...); then the
    C++ loader reads it exactly as `lash run` does and raises `ModelError` with every problem.
    """

    def __init__(self, text: Optional[str] = None, *, filename: str = "<model>",
                 data: Optional[dict] = None, overrides: str | Sequence[str] = ()) -> None:
        """Use `lash.load(path)`, `lash.loads(text)` or `Model.new(name)` rather than this."""
        if text is not None:
            _string("text", text, "the text of a model file (str)")
            if data is not None:  # the text was used and the data dropped without a word
                raise ValueError("give a model's text or its data, not both")
        _string("filename", filename, "a file name for messages (str)")
        self._text = text
        self._data = data
        self.filename = filename
        self.overrides: List[str] = _override_list(overrides)
        self._compiled = None
        self._compiled_from = None  # (text, overrides) the cached compiled model was loaded from

    # --- construction --------------------------------------------------------------------
    @classmethod
    def new(cls, name: str, *, gravity: Optional[Sequence[float]] = None) -> "Model":
        """An empty model named `name`, to be built with add_body, add_joint, ... Gravity is off
        unless given, as in a model file (docs/model-format.md §2): gravity=[0, -9.81] (m/s^2)."""
        _string("name", name, "the model's name (str)")
        data: Dict[str, Any] = {"name": name}
        if gravity is not None:
            if isinstance(gravity, (str, bytes)) or not isinstance(gravity, (Sequence, np.ndarray)):
                raise TypeError(f"gravity: expected a pair of numbers [x, y] (m/s^2), got "
                                f"{_short(gravity)} ({type(gravity).__name__})")
            data["gravity"] = list(gravity)
        data.update({"bodies": {}, "joints": {}})
        return cls(data=data, filename=f"<{name}>")

    @property
    def data(self) -> dict:
        """The model as Python data (dicts and lists as in the model file, overrides not applied).

        Reading it from a loaded file drops the file's comments from what `save` writes."""
        if self._data is None:
            try:
                self._data = _lash.parse_yaml(self._text or "", _message_name(self.filename)) or {}
            except RuntimeError as e:  # yaml-cpp's parser: "yaml-cpp: error at line 3, column 5: ..."
                m = re.match(r"yaml-cpp: error at line (\d+), column (\d+): (.*)", str(e), re.S)
                line, column, what = (int(m.group(1)), int(m.group(2)), m.group(3)) if m else (0, 0, str(e))
                file = _message_name(self.filename)
                error = ModelError(f"{file}{f':{line}:{column}' if m else ''}: not valid YAML: {what}\n")
                error.diagnostics = [(file, line, column, "", f"not valid YAML: {what}")]
                raise error from None
            self._text = None
        self._compiled = None  # the caller may change it
        return self._data

    def _section(self, key: str) -> dict:
        section = self.data.setdefault(key, {})
        if section is None:
            section = self.data[key] = {}
        return section

    def _add(self, key: str, name: str, spec: dict) -> "Model":
        section = self._section(key)
        if name in section:
            raise ValueError(f"{_ELEMENT_KIND.get(key, key)} '{name}' exists already")
        section[name] = {k: v for k, v in spec.items() if v is not None}
        return self

    def add_ground_marker(self, name: str, position: Sequence[float]) -> "Model":
        """A named point on the ground, world coordinates in m (`ground.markers`)."""
        ground = self._section("ground")
        markers = ground.setdefault("markers", {})
        if markers is None:
            markers = ground["markers"] = {}
        if name in markers:
            raise ValueError(f"ground marker '{name}' exists already")
        markers[name] = _point(f"ground marker '{name}'", position)
        return self

    def add_body(self, name: str, *, mass: float, inertia: Optional[float] = None,
                 position: Sequence[float] = (0.0, 0.0), angle: Optional[float] = None,
                 markers: Optional[Dict[str, Sequence[float]]] = None, **more: Any) -> "Model":
        """A rigid body (mass kg, inertia kg*m^2 about the centre of mass, position of the centre
        of mass m, angle rad, markers in body coordinates m); `more` holds any other key of
        docs/model-format.md (e.g. type="point_mass", velocity=[vx, vy])."""
        if markers is not None and not isinstance(markers, Mapping):
            raise TypeError(f"markers: expected a dict of marker name to [x, y] (m, body "
                            f"coordinates), got {_short(markers)} ({type(markers).__name__})")
        spec = {"mass": None if mass is None else _real("mass", mass, "a number (kg)"),
                "inertia": None if inertia is None else _real("inertia", inertia, "a number (kg*m^2)"),
                "position": _point("position", position),
                "angle": None if angle is None else _real("angle", angle, "a number (rad)"),
                "markers": {k: _point(f"marker '{k}'", v) for k, v in (markers or {}).items()} or None}
        spec.update(more)
        return self._add("bodies", name, spec)

    def add_joint(self, name: str, type: str = "revolute", **spec: Any) -> "Model":
        """A joint: type revolute (journal="body.marker", bearing="body.marker"), translational
        (guide=, slider=, axis=[x, y]), fixed or distance, with the keys of docs/model-format.md."""
        return self._add("joints", name, {"type": type, **spec})

    def add_clearance_joint(self, name: str, *, journal: str, bearing: str, clearance: float,
                            **spec: Any) -> "Model":
        """A revolute joint with radial clearance `clearance` (m) between the journal and the
        bearing; contact and friction keys (journal_radius, normal_law, restitution, friction,
        material, ...) as in docs/model-format.md, or from `clearance_defaults`."""
        return self._add("joints", name, {"type": "revolute", "journal": journal,
                                          "bearing": bearing,
                                          "clearance": _real("clearance", clearance, "a number (m)"),
                                          **spec})

    def set_clearance_defaults(self, **spec: Any) -> "Model":
        """Defaults of every clearance joint (`clearance_defaults`: journal_radius, material, ...);
        a value None removes the key (the model file's default)."""
        _update(self._section("clearance_defaults"), spec)
        return self

    def add_driver(self, name: str, **spec: Any) -> "Model":
        """A driver, e.g. add_driver("crank", joint="crank_pivot", speed_rpm=5000)."""
        return self._add("drivers", name, spec)

    def add_load(self, name: str, **spec: Any) -> "Model":
        """A load (force, torque, spring_damper, ...), keys as in docs/model-format.md."""
        return self._add("loads", name, spec)

    def set_solver(self, **spec: Any) -> "Model":
        """Solver settings: integrator, rtol, atol, end_time, output_interval, initial_state, ...;
        a value None removes the key (the model file's default)."""
        _update(self._section("solver"), spec)
        return self

    # --- overrides and the compiled model ------------------------------------------------
    def set(self, path: str, value: Any) -> "Model":
        """Changes one value as the CLI's `--set path=value` does, e.g.
        model.set("joints.rod_slider.clearance", 0.25e-3). Checked when the model is next used;
        a path that does not exist raises ModelError there."""
        if not isinstance(path, str):
            raise TypeError(f"path: expected a dotted path string such as "
                            f"\"joints.rod_slider.clearance\", got {type(path).__name__}")
        if "=" in path:
            raise ValueError(f"path '{path}' contains '='; pass the value separately")
        self.overrides.append(f"{path}={_yaml_value(value)}")
        self._compiled = None
        return self

    def copy(self) -> "Model":
        """An independent copy (its own overrides and data); copy.copy(model) makes the same (a
        shallow copy shared the overrides list, so setting a value on one set it on both)."""
        import copy as _copy
        twin = Model(filename=self.filename, data=_copy.deepcopy(self._data),
                     overrides=self.overrides)
        twin._text = self._text
        return twin

    __copy__ = copy

    def text(self) -> str:
        """The model file's text, overrides not applied."""
        return self._text if self._text is not None else _lash.emit_yaml(_plain(self._data))

    def compiled(self, extra_overrides: str | Sequence[str] = (),
                 keywords: Optional[Dict[str, str]] = None):
        """The model loaded and validated by the C++ loader (cached); raises ModelError.
        `keywords` (model path -> argument name) names the overrides a function's keyword
        arguments made after those arguments in the error."""
        # A loaded file whose data was read or changed in code is loaded from that data written
        # again: its line numbers are those of Model.text(), not of the file, and it is named so.
        name = _message_name(self.filename)
        if self._text is None and not self.filename.startswith("<"):
            name = f"<{name}, edited: lines of Model.text()>"
        text, overrides = self.text(), self.overrides + _override_list(extra_overrides)
        # Python strings may hold lone surrogates (a file name or bytes decoded with
        # surrogateescape); the loader takes UTF-8 text only.
        for what, value in [("the model's text", text)] + [(f"override {o!r}", o) for o in overrides]:
            try:
                value.encode("utf-8")
            except UnicodeEncodeError as e:
                raise ValueError(f"{what[:200]}: not valid UTF-8 text (character {e.start}, "
                                 f"{value[e.start]!r}); give text without lone surrogates") from None
        try:
            if extra_overrides:
                return _lash.load_text(text, name, overrides)
            # Loaded again whenever the text or the overrides differ from the cached model's:
            # `data` may be changed in place through a dict the caller kept.
            key = (text, tuple(overrides))
            if self._compiled is None or self._compiled_from != key:
                self._compiled = _lash.load_text(text, name, overrides)
                self._compiled_from = key
        except ModelError as e:
            raise _python_diagnostics(e, keywords or {}, overrides) from None
        return self._compiled

    def check(self) -> "Model":
        """Validates and assembles the model as `lash check` does: raises ModelError listing
        every problem of the file, RuntimeError (file:line: element) when no initial state
        satisfies its joints and drivers, and issues what assembly warns of (a redundant joint
        equation, a body moved far from its given pose) as Python warnings (UserWarning)."""
        import warnings
        for message in _lash.assemble(self.compiled()):
            warnings.warn(message, stacklevel=2)
        return self

    @property
    def name(self) -> str:
        """The model's name (its `name` key, else the file's stem), as summary.json has it."""
        return self.compiled().name

    @property
    def channels(self) -> List[str]:
        """Every output channel `<element>.<quantity>`, in the column order of timeseries.csv
        (a Result holds every channel: solver.output_channels selects only what `lash run`
        writes)."""
        return [c[0] for c in self.compiled().channels]

    def resolved_yaml(self) -> str:
        """The model as it runs, overrides applied (what `lash run` writes to model_resolved.yaml)."""
        return self.compiled().resolved_yaml

    def save(self, path: str | os.PathLike) -> None:
        """Writes the model file: the text as loaded when nothing changed (comments kept), else
        the model with its overrides applied. Validated first, so no broken file is written."""
        if not isinstance(path, (str, os.PathLike)):  # open() takes an int as a descriptor
            raise TypeError(f"path: expected a file name (str or os.PathLike), got {path!r} "
                            f"({type(path).__name__})")
        compiled = self.compiled()
        text = self._text if (self._text is not None and not self.overrides) else compiled.resolved_yaml
        with open(path, "w", encoding="utf-8") as f:
            f.write(text if text.endswith("\n") else text + "\n")

    def __getstate__(self) -> dict:
        # Pickled (multiprocessing, copy.deepcopy) as text, data and overrides: the compiled
        # model is loaded again where it is used.
        state = dict(self.__dict__)
        state["_compiled"] = state["_compiled_from"] = None
        return state

    def __repr__(self) -> str:
        return f"<lash.Model {self.filename!r}, {len(self.overrides)} overrides>"


def load(path: str | bytes | os.PathLike, overrides: str | Iterable[str] = ()) -> Model:
    """Reads a model file (YAML, docs/model-format.md) and validates it.

    `overrides` are "KEY.PATH=VALUE" strings as for `lash run --set` (a single string is one
    override). As `lash check`, the file must be a regular file of at most 16 MiB (not a folder,
    a FIFO or a device such as /dev/zero) and UTF-8 text, checked before it is read; its name may
    be any file name (bytes that are not UTF-8 included: `Model.filename` is then os.fsdecode's
    str, and messages show those bytes as \\xNN). Raises ModelError with every problem as
    `file:line:column: element: message` (also as `.diagnostics`, a list of (file, line, column,
    element, message)), FileNotFoundError (an OSError) when there is no such file, IoError (an
    OSError) when it cannot be read."""
    if not isinstance(path, (str, bytes, os.PathLike)):
        raise TypeError(f"path: expected a model file path (str, bytes or os.PathLike), got "
                        f"{_short(path)} ({type(path).__name__})")
    raw = os.fsencode(path)
    filename = os.fsdecode(raw)
    name = _message_name(filename)
    os.stat(filename)  # FileNotFoundError, PermissionError, ... with the path as given
    data = _lash.read_model_file(raw, name)  # a regular file, not too large: as `lash check`
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError:
        text = None
    if text is None:
        # The loader's ModelError, with line and column: "not UTF-8 text (byte 0xE9)".
        try:
            _lash.load_text(data, name, _override_list(overrides))
        except ModelError as e:
            raise _python_diagnostics(e, {}) from None
        error = ModelError(f"{name}: not UTF-8 text")  # the loader found nothing wrong
        error.diagnostics = [(name, 0, 0, "", "not UTF-8 text")]
        raise error
    model = Model(text, filename=filename, overrides=overrides)
    model.compiled()  # validated as the loader reads it; assembled when used (or by check())
    return model


def loads(text: str, filename: str = "<string>", overrides: str | Iterable[str] = ()) -> Model:
    """As `load`, from the text of a model file; `filename` is used in messages."""
    _string("text", text, "the text of a model file (str)")
    model = Model(text, filename=filename, overrides=overrides)
    model.compiled()
    return model


class Result:
    """The outputs of one run, in memory.

    result["slider.ax"]  one channel as a NumPy array (a read-only view of `values`, no copy)
    result.time          output times, s
    result.values        every channel, shape (outputs, channels), columns as `channels`
    result.channels      channel names; `units` and `descriptions` beside them
    result.events        contact onsets and separations: dict of arrays time, joint, event
                         ("onset"/"separation"), velocity (m/s)
    result.summary       dict as summary.json: status, channels (min/max/peak with times),
                         clearance_joints (impacts, contact share), integrator statistics
    result.status        dict: outcome (completed, failed, interrupted), ok, time, element, message
    """

    def __init__(self, model: Model, compiled, raw: dict, overrides: Sequence[str] = ()) -> None:
        self.model = model
        # What the summary and the analyses need of the compiled model (a Result pickles).
        self._model_name: str = compiled.name
        self._clearance_joint_names: List[str] = list(compiled.clearance_joints)
        self._resolved_yaml: str = compiled.resolved_yaml
        self._overrides = list(overrides)  # every override of the run, simulate's included
        self.time: np.ndarray = raw["time"]
        self.values: np.ndarray = raw["values"]
        self.channels: List[str] = [c[0] for c in compiled.channels]
        self.units: Dict[str, str] = {c[0]: c[1] for c in compiled.channels}
        self.descriptions: Dict[str, str] = {c[0]: c[2] for c in compiled.channels}
        self._index = {name: i for i, name in enumerate(self.channels)}
        ev = raw["events"]
        self.events: Dict[str, Any] = {
            "time": ev["time"], "joint": np.array(ev["joint"], dtype=object),
            "event": np.where(ev["onset"], "onset", "separation").astype(object),
            "velocity": ev["velocity"]}
        # Read-only: the channels are views of `values`, and the summary is computed from them
        # on first use; a write through one (ax /= 9.81) would change every view and the summary.
        for array in (self.time, self.values, *self.events.values()):
            array.setflags(write=False)
        self.status: Dict[str, Any] = raw["status"]
        self.integrator: Dict[str, Any] = raw["integrator"]
        self.max_constraint_violation: float = raw["max_constraint_violation"]
        self.warnings: List[str] = raw["warnings"]
        self.final_state: Dict[str, Any] = raw["final_state"]
        self._initial_contact = raw["initial_contact"]
        # Exact extrema tracked between outputs (as in summary.json); absent: from the rows.
        self._extrema = raw.get("extrema")
        # solver, peaks and each clearance joint's parameters, as `lash run` writes them.
        self._blocks = json.loads(raw["summary_blocks"])
        self._summary: Optional[dict] = None

    def __setstate__(self, state: dict) -> None:
        # Unpickled arrays come back writable: read-only again, as built.
        self.__dict__.update(state)
        for array in (self.time, self.values, *self.events.values()):
            array.setflags(write=False)

    def __getitem__(self, channel: str) -> np.ndarray:
        """One channel's values at `time` (a view, SI units)."""
        if not isinstance(channel, str):
            raise TypeError(f"a Result is indexed by a channel name such as "
                            f"'{self.channels[0] if self.channels else 'slider.ax'}', got "
                            f"{channel!r} ({type(channel).__name__}); rows are result.values[i]")
        try:
            return self.values[:, self._index[channel]]
        except KeyError:
            import difflib
            # Case aside first ("slider.AX" is "slider.ax", not "slider.y").
            near = [c for c in self.channels if c.lower() == channel.lower()] or \
                difflib.get_close_matches(channel, self.channels, n=1)
            hint = f", did you mean '{near[0]}'?" if near else ""
            raise KeyError(f"no channel '{channel}' in this run{hint}") from None

    def __contains__(self, channel: str) -> bool:
        return channel in self._index

    def __len__(self) -> int:
        return len(self.time)

    @property
    def ok(self) -> bool:
        """True when the run reached end_time."""
        return bool(self.status["ok"])

    @property
    def summary(self) -> Dict[str, Any]:
        """What `lash run` writes to summary.json, computed from these arrays: status, per
        channel unit/description/min/t_min/max/t_max/peak, per clearance joint impacts,
        separations, contact and free-flight shares, max impact velocity, integrator statistics."""
        if self._summary is None:
            self._summary = self._make_summary()
        return self._summary

    def _make_summary(self) -> Dict[str, Any]:
        channels = {}
        for i, name in enumerate(self.channels):
            col = self.values[:, i]
            if len(col) == 0:
                continue
            i_min, i_max = int(np.argmin(col)), int(np.argmax(col))
            lo, hi = float(col[i_min]), float(col[i_max])
            t_lo, t_hi = float(self.time[i_min]), float(self.time[i_max])
            if self._extrema is not None:  # tracked between outputs, as `lash run` does
                lo, hi = float(self._extrema["min"][i]), float(self._extrema["max"][i])
                t_lo, t_hi = float(self._extrema["t_min"][i]), float(self._extrema["t_max"][i])
            channels[name] = {"unit": self.units[name], "description": self.descriptions[name],
                              "min": lo, "t_min": t_lo, "max": hi,
                              "t_max": t_hi, "peak": max(abs(lo), abs(hi))}
        joints = {}
        t_first = float(self.time[0]) if len(self.time) else 0.0
        t_last = float(self.time[-1]) if len(self.time) else 0.0
        span = t_last - t_first
        for k, joint in enumerate(self._clearance_joint_names):
            mask = self.events["joint"] == joint
            times, kinds = self.events["time"][mask], self.events["event"][mask]
            vel = self.events["velocity"][mask]
            in_contact = bool(self._initial_contact[k]) if k < len(self._initial_contact) else False
            onset_t, contact = t_first, 0.0
            for t, kind in zip(times, kinds):
                if kind == "onset":
                    in_contact, onset_t = True, t
                else:
                    if in_contact:
                        contact += t - onset_t
                    in_contact = False
            if in_contact:
                contact += t_last - onset_t
            share = contact / span if span > 0 else 0.0
            onsets = kinds == "onset"
            joints[joint] = {"impacts": int(onsets.sum()), "separations": int((~onsets).sum()),
                             "contact_share": share, "free_flight_share": 1.0 - share,
                             "max_impact_velocity": float(vel[onsets].max()) if onsets.any() else 0.0,
                             **self._blocks.get("clearance_parameters", {}).get(joint, {})}
        return {"status": dict(self.status), "channels": channels, "clearance_joints": joints,
                "integrator": dict(self.integrator), "solver": self._blocks["solver"],
                "peaks": self._blocks["peaks"],
                "max_constraint_violation": self.max_constraint_violation,
                "model": {"name": self._model_name, "file": self.model.filename,
                          "overrides": list(self._overrides), **self._blocks["model_counts"],
                          "resolved": self._resolved_yaml}}

    def to_pandas(self):
        """The time series as a pandas DataFrame indexed by time (needs pandas, e.g. Debian's
        python3-pandas); raises ImportError without it. The frame holds a copy of the values,
        so it can be edited (the Result's own arrays are read-only)."""
        try:
            import pandas as pd
        except ImportError as e:
            raise ImportError("Result.to_pandas needs pandas (apt-get install python3-pandas)") from e
        df = pd.DataFrame(self.values, columns=self.channels, copy=True)
        df.index = pd.Index(self.time.copy(), name="time")
        return df

    def events_to_pandas(self):
        """The events as a pandas DataFrame (columns time, joint, event, velocity)."""
        import pandas as pd
        return pd.DataFrame(self.events)

    def __repr__(self) -> str:
        return (f"<lash.Result {self.status['outcome']} at t={self.status['time']:g} s, "
                f"{len(self.time)} outputs x {len(self.channels)} channels, "
                f"{len(self.events['time'])} events>")


def _as_model(model: Model | str | bytes | os.PathLike) -> Model:
    if isinstance(model, Model):
        return model
    if isinstance(model, (str, bytes, os.PathLike)):
        return load(model)
    raise TypeError(f"expected a lash.Model or a model file path, got {type(model).__name__}")


# The model paths that simulate's keyword arguments set.
_RUN_KEYWORDS = {"solver.end_time": "t_end", "solver.output_interval": "output_interval",
                 "solver.integrator": "integrator"}


def _run_overrides(t_end: Optional[float], output_interval: Optional[float],
                   integrator: Optional[str], overrides: str | Iterable[str]) -> List[str]:
    extra = _override_list(overrides)
    # A keyword and an override of this call setting one value: which was meant is not known
    # (the keyword won, and the override's value was never checked).
    for name, value, path in (("t_end", t_end, "solver.end_time"),
                              ("output_interval", output_interval, "solver.output_interval"),
                              ("integrator", integrator, "solver.integrator")):
        same = [o for o in extra if o.split("=", 1)[0].strip() == path]
        if value is not None and same:
            raise ValueError(f"{name} sets {path}, and so does the override '{same[0]}': give "
                             f"one of them")
    # Any real number (NumPy's included), checked by value after its type.
    for name, value, path in (("t_end", t_end, "solver.end_time"),
                              ("output_interval", output_interval, "solver.output_interval")):
        if value is None:
            continue
        seconds = _real(name, value, "a number (s)")
        if not (math.isfinite(seconds) and seconds > 0):
            raise ValueError(f"{name} must be a finite time > 0 s, got {seconds!r}")
        extra.append(f"{path}={_yaml_value(seconds)}")
    if integrator is not None:
        if not isinstance(integrator, str):
            raise TypeError(f"integrator: expected a name such as \"dopri5\" or \"bdf\", got "
                            f"{type(integrator).__name__}")
        extra.append(f"solver.integrator={integrator}")
    return extra


def _python_diagnostics(error: ModelError, keywords: Dict[str, str],
                        overrides: Sequence[str] = ()) -> ModelError:
    """`error` in Python's terms. The C++ loader names an override as the CLI's option,
    "--set solver.end_time", and a value it set "(value set with --set)". Here an override
    that a keyword argument made (`keywords`: model path -> argument) is named as that
    argument, "t_end (solver.end_time)", and any other (Model.set, an `overrides` string) as
    "override solver.end_time", "(value set by an override)". The same error when it names no
    override."""
    set_with = " (value set with --set)"  # the loader's note on a value from an override
    diagnostics, changed = [], False
    for file, line, column, element, message in error.diagnostics:
        if file.startswith("--set ") and file[len("--set "):] in keywords:
            path = file[len("--set "):]
            file, changed = f"{keywords[path]} ({path})", True
        elif file == "--set" or file.startswith("--set "):
            file, changed = "override" + file[len("--set"):], True
        # What the message is about: not the keys it lists or suggests ("unknown key 'foo',
        # expected one of: integrator, rtol, ..., end_time, ...").
        about = re.split(r", expected one of|, did you mean", message)[0]
        def names(path: str) -> bool:  # a solver message about the key `path` sets
            return element == "solver" and re.search(rf"\b{path.split('.')[-1]}\b", about)
        if not message.endswith(set_with) and not file.startswith("override"):
            # A value of the file checked against one an argument set ("output_interval must
            # be <= end_time, got 1e-05 > 1e-09" where t_end set end_time): say which.
            named = [f"{p.split('.')[-1]} from the argument {k}" for p, k in keywords.items()
                     if names(p)]
            if named:
                message, changed = message + f" ({'; '.join(named)})", True
        if message.endswith(set_with):
            # A solver value: the key the message is about opens it ("output_interval must be
            # > 0", "'end_time' must be a number", "unknown integrator 'rk4'").
            # The arguments whose key the message names ("end_time / output_interval = 2.4e+10
            # outputs, more than max_outputs" names both), and the overrides of solver keys
            # that it names (a bad output_interval override beside t_end).
            named = [k for p, k in keywords.items() if names(p)]
            others = sorted({p for p in (o.split("=", 1)[0] for o in overrides)
                             if p.startswith("solver.") and p not in keywords and names(p)})
            what = [f"the argument {k}" for k in named] + [f"the override {p}" for p in others]
            message = message[:-len(set_with)] + (
                f" (value of {what[0]})" if len(what) == 1 else
                f" (values of {' and '.join(what)})" if what else
                " (value set by an override)")
            changed = True
        diagnostics.append((file, line, column, element, message))
    if not changed:
        return error
    # As the C++ Diagnostic::str: file[:line:column]: [element: ]message, one a line.
    text = "".join(f"{f}{f':{l}:{c}' if l > 0 else ''}: {e + ': ' if e else ''}{m}\n"
                   for f, l, c, e, m in diagnostics)
    renamed = ModelError(text)
    renamed.diagnostics = diagnostics
    return renamed


def simulate(model: Model | str | os.PathLike, t_end: Optional[float] = None, *,
             output_interval: Optional[float] = None, integrator: Optional[str] = None,
             overrides: str | Iterable[str] = (), start: Any = None) -> Result:
    """Runs `model` from t = 0 to `t_end` (s; default the model's solver.end_time) and returns
    its outputs in memory as a `Result`, the same numbers `lash run` writes to timeseries.csv.

    start continues a run instead, time and all, to t_end (later than the state's time): a
    `Result` (where it ended), its `final_state`, or the path of a final_state.json that
    `lash run` wrote (as `lash run --from`); a state that does not fit the model raises
    ValueError naming what differs, a file that cannot be read IoError (an OSError).

    output_interval (s) and integrator ("dopri5" or "bdf") override the model's solver
    settings, `overrides` are more "KEY.PATH=VALUE" strings (a single string is one override;
    one that sets what a keyword given sets is refused); `model` itself is not changed.
    The GIL is released while the engine runs. Ctrl-C (SIGINT) stops the run within one integrator step
    and raises KeyboardInterrupt. A numerical failure does not raise: the result holds the run up
    to the failure and `result.status` says what happened (`result.ok` is False).
    Raises ModelError for a bad model or override, RuntimeError when no consistent initial state
    exists."""
    model = _as_model(model)
    extra = _run_overrides(t_end, output_interval, integrator, overrides)
    # A path the caller also set in an override string keeps the name "override".
    set_by_caller = {o.split("=", 1)[0] for o in model.overrides + _override_list(overrides)}
    given = {"t_end": t_end, "output_interval": output_interval, "integrator": integrator}
    keywords = {p: k for p, k in _RUN_KEYWORDS.items()
                if given[k] is not None and p not in set_by_caller}
    compiled = model.compiled(extra, keywords)
    if isinstance(start, Result):
        start = start.final_state
    elif isinstance(start, (str, os.PathLike)):
        start = os.fsdecode(start)
    elif start is not None and not isinstance(start, Mapping):
        raise TypeError(f"start: expected a Result, its final_state or the path of a "
                        f"final_state.json, got {type(start).__name__}")
    try:
        raw = _lash.simulate(compiled, dict(start) if isinstance(start, Mapping) else start)
    except TypeError:  # an entry of `start` of the wrong type, named
        raise
    except ValueError as e:  # a state that does not fit: as `--from` says it, in Python's terms
        raise ValueError(str(e).replace("raise it with --set solver.end_time=...",
                                        "give a later t_end")) from None
    return Result(model, compiled, raw, model.overrides + extra)


class Study:
    """The results of a parameter study (`lash sweep`), read from its study.db.

    study.rows        one dict per recorded run: "run", each parameter, "status", "verdict",
                      "message", "wall_seconds" and every metric (docs/studies.md)
    study.parameters  the parameter names (model paths or case names)
    study.sections    {channel: {"run": [...], "value": [...]}}: the points of the bifurcation
                      diagram, after the transient
    study["x"]        one column over the runs as a NumPy array (NaN where a run lacks it)
    study.to_pandas() the rows as a pandas DataFrame (pandas needed)
    """

    def __init__(self, db_path: str | os.PathLike) -> None:
        # Bytes to the engine: a path that is not UTF-8 (surrogate escapes in a str) is no
        # str pybind11 can pass on.
        data = _lash.read_study(os.fsencode(db_path))
        self.path = os.fsdecode(db_path)
        self.name: str = data["name"]
        self.total_runs: int = data["total_runs"]
        self.parameters: List[str] = list(data["parameters"])
        self.rows: List[Dict[str, Any]] = list(data["rows"])
        self.sections: Dict[str, Dict[str, Any]] = {
            k: {"run": np.asarray(v["run"], dtype=int), "value": np.asarray(v["value"], dtype=float)}
            for k, v in data["sections"].items()}

    def __len__(self) -> int:
        return len(self.rows)

    def __getitem__(self, column: str) -> np.ndarray:
        if not isinstance(column, str):  # study[1] said "1: no run has it"
            raise TypeError(f"study[...] takes a column name (str), got {_short(column)} "
                            f"({type(column).__name__}); one run's values are study.rows[i]")
        if self.rows and not any(column in row for row in self.rows):
            raise KeyError(f"{column!r}: no run has it; columns: {sorted(set().union(*self.rows))}")
        values = [row.get(column, math.nan) for row in self.rows]
        if all(isinstance(v, (int, float)) for v in values):
            return np.asarray(values, dtype=float)
        return np.asarray(values, dtype=object)

    def to_pandas(self):
        """The rows as a pandas DataFrame indexed by run."""
        import pandas as pd
        return pd.DataFrame(self.rows).set_index("run")

    def __repr__(self) -> str:
        failed = sum(1 for r in self.rows if r["status"] != "completed")
        return f"<lash.Study {self.name!r}: {len(self.rows)} of {self.total_runs} runs, {failed} failed>"


def sweep(study: str | os.PathLike, output: str | os.PathLike, *, jobs: Optional[int] = 0,
          resume: bool = False) -> Study:
    """Runs a study file (docs/studies.md) on `jobs` local threads (0: every core), as
    `lash sweep STUDY -o OUTPUT [--resume]`: every finished run is written to OUTPUT/study.db in
    its own transaction, runs.csv and sections.csv beside it. Returns the Study read back.
    `jobs=0` (the default) or None: every core. Paths may be str, bytes or os.PathLike.

    Raises OSError (FileNotFoundError, ...) when the study file cannot be read, ModelError (with
    file:line:column) for a bad study file, ValueError when OUTPUT holds a
    study already and `resume` is False (or holds another study), IoError when the database cannot
    be written. Ctrl-C stops the runs within one integrator step; the finished ones stay recorded
    and `resume=True` runs the rest.
    """
    if jobs is None:
        jobs = 0
    if isinstance(jobs, bool) or not isinstance(jobs, (int, np.integer)):
        raise TypeError(f"jobs: expected a number of threads (0 or None: every core), got "
                        f"{jobs!r} ({type(jobs).__name__})")
    if not 0 <= jobs <= 4096:
        raise ValueError(f"jobs={jobs}: expected 0 (every core) or a number of threads up to 4096")
    resume = _flag("resume", resume)
    for name, value in (("study", study), ("output", output)):
        if not isinstance(value, (str, bytes, os.PathLike)):
            raise TypeError(f"{name}: expected a path (str, bytes or os.PathLike), got "
                            f"{_short(value)} ({type(value).__name__})")
    output = os.fsdecode(output)
    if not output:
        raise ValueError("output: expected a folder name")
    study = os.fsdecode(study)
    with open(study, "rb"):  # FileNotFoundError, IsADirectoryError, ... with the path
        pass
    try:
        _lash.sweep(os.fsencode(study), os.fsencode(output), int(jobs), resume)
    except ValueError as e:
        if "add --resume" not in str(e):  # the CLI's option, resume=True here
            raise
        raise type(e)(str(e).replace("add --resume", "pass resume=True")) from None
    return Study(os.path.join(output, "study.db"))


def read_study(output: str | os.PathLike) -> Study:
    """The Study in a folder written by `lash sweep` (or its study.db)."""
    path = os.fsdecode(output)
    return Study(path if path.endswith(".db") else os.path.join(path, "study.db"))


from . import analysis  # noqa: E402  (uses Model and Result above)
