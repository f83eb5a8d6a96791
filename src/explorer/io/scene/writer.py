"""Writing a scene back as TOML text (:meth:`Scene.to_toml <explorer.io.scene.Scene.to_toml>`)."""
from __future__ import annotations

import json
import numbers

from explorer.io.scene.schema import _TOP_KEYS


def scene_toml(d: dict) -> str:
    """TOML text of a scene's :meth:`~explorer.io.scene.Scene.to_dict` (tables in the order of the format)."""
    out = []
    for k in ("name", "description"):
        out.append(f"{k} = {_toml_value(d[k])}")
    for table in _TOP_KEYS[2:]:
        if table in d:
            out.append(f"\n[{table}]")
            out.extend(f"{k} = {_toml_value(v)}" for k, v in d[table].items())
    return "\n".join(out) + "\n"


def _toml_string(s: str) -> str:
    r = json.dumps(s, ensure_ascii=False)  # TOML basic strings share JSON's escapes
    return r.replace("\x7f", "\\u007f")


def _toml_value(v) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, numbers.Integral):
        return str(int(v))
    if isinstance(v, float):
        return repr(v)
    if isinstance(v, str):
        return _toml_string(v)
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    raise TypeError(f"cannot write {v!r} as TOML")

