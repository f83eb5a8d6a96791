"""The scene's validators: each value checked under its dotted key, refusals as :class:`SceneError`."""
from __future__ import annotations

from explorer.io.scene.schema import _NAME_RE, MAX_NAME_LENGTH
from explorer.model import ParameterError, validation


class SceneError(ParameterError):
    """Bad scene: a one-line message naming the dotted key and what is allowed."""


def _short(v, limit=60) -> str:
    r = repr(v)
    return r if len(r) <= limit else r[: limit - 3] + "..."


def _fail(key, msg):
    raise SceneError(f"scene key '{key}' {msg}")


def _got(v) -> str:
    return f"got {_short(v)} ({type(v).__name__})"


def _checked(check, key, *args, **kwargs):
    """A value checked by :mod:`explorer.model.validation`, its refusal as a SceneError."""
    try:
        return check(f"scene key '{key}'", *args, **kwargs)
    except ParameterError as exc:
        raise SceneError(str(exc)) from None


def _real(key, v, lo=None, hi=None, lo_open=False) -> float:
    """A finite real number (int or float, not bool) in [lo, hi] (or (lo, hi] if lo_open)."""
    return _checked(validation.real, key, v, lo, hi, lo_open=lo_open)


def _int(key, v, lo=None, hi=None) -> int:
    return _checked(validation.integer, key, v, lo, hi)


def _bool(key, v) -> bool:
    return _checked(validation.boolean, key, v)


def _str(key, v) -> str:
    if not isinstance(v, str):
        _fail(key, f"must be a string, {_got(v)}")
    return v


def _scene_name(v) -> str:
    """A scene's ``name``: [A-Za-z0-9_.-]+, not starting with '.', at most MAX_NAME_LENGTH characters."""
    name = _str("name", v)
    if not _NAME_RE.match(name) or name.startswith(".") or len(name) > MAX_NAME_LENGTH:
        _fail("name", f"must match [A-Za-z0-9_.-]+, not start with '.', and have at most "
              f"{MAX_NAME_LENGTH} characters; got {_short(name)}")
    return name


def _own_scale(figure, n_panels: int) -> None:
    """[figure] own_scale names panels of the scene."""
    for j, idx in enumerate(figure.own_scale):
        if idx >= n_panels:
            _fail(f"figure.own_scale[{j}]", f"must be a panel index in [0, {n_panels - 1}], got {idx}")


def _choice(key, v, choices) -> str:
    return _checked(validation.choice, key, v, choices)


def _list(key, v, min_len=1) -> list:
    if not isinstance(v, (list, tuple)):
        _fail(key, f"must be a list, {_got(v)}")
    if len(v) < min_len:
        _fail(key, "must be a non-empty list" if min_len == 1 else f"must have at least {min_len} items")
    return list(v)


def _distinct_reals(key, seq) -> tuple:
    """The finite reals of the list ``key``, each once (a repeated value names both places)."""
    values: list = []
    for i, v in enumerate(_list(key, seq)):
        x = _real(f"{key}[{i}]", v)
        if x in values:
            _fail(f"{key}[{i}]", f"duplicates {key}[{values.index(x)}] = {x!r}")
        values.append(x)
    return tuple(values)


def _swept(scene, table, choices) -> bool:
    """The swept parameter of the scene's [sweep] or [atlas] ``table``: False, its values cleared,
    when none is given (values without one are refused); True once it is one of ``choices``."""
    parameter = getattr(scene, f"{table}_parameter")
    if parameter is None:
        if len(getattr(scene, f"{table}_values")):
            _fail(f"{table}.parameter", f"is required when {table} values are given")
        object.__setattr__(scene, f"{table}_values", ())
        return False
    _choice(f"{table}.parameter", parameter, choices)
    return True


def _table(key, v, allowed) -> dict:
    """Check that ``v`` is a table whose keys are all in ``allowed``."""
    if not isinstance(v, dict):
        _fail(key, f"must be a table, {_got(v)}")
    for k in v:
        if k not in allowed:
            raise SceneError(f"scene: unknown key '{key}.{k}'{validation.did_you_mean(k, allowed)} "
                             f"(allowed: {', '.join(allowed)})")
    return v



def _sweep(data: dict) -> dict:
    """A scene's ``[sweep]`` table (both keys required) as ``sweep_parameter`` and ``sweep_values``;
    {} without one."""
    if "sweep" not in data:
        return {}
    sweep = _table("sweep", data["sweep"], ("parameter", "values"))
    for k in ("parameter", "values"):
        if k not in sweep:
            _fail(f"sweep.{k}", "is required in a [sweep] table")
    return {"sweep_parameter": _str("sweep.parameter", sweep["parameter"]),
            "sweep_values": tuple(_list("sweep.values", sweep["values"]))}
