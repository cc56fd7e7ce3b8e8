"""The system stored under a description key (see :mod:`conmech.symbolic.description`),
loaded from the derivation cache without any derivation: the fast path of a tree or robot built
again from the same description."""
import os
import time

from .build import _read_json
from .description import _entry
from .pipeline import _from_cache, _system


def description_hit(dkey, flags, model_only, params=None):
    """The system (``model_only``: the CompiledModel) stored under the description key,
    loaded without any derivation, or None. `params`: the caller's parameter values (a
    tree's); None: the values stored with the entry (a robot's)."""
    if dkey is None:
        return None
    t0 = time.perf_counter()
    path = _entry(dkey)
    if not os.path.isfile(path):
        return None
    info = _read_json(path)
    if not isinstance(info, dict):
        return None
    key, stored = info.get("key"), info.get("params")
    if not (isinstance(key, str) and len(key) == 64 and
            all(c in "0123456789abcdef" for c in key)):
        return None
    if params is None:
        if not (isinstance(stored, list) and all(
                isinstance(p, list) and len(p) == 2 and isinstance(p[0], str) and
                isinstance(p[1], (int, float)) and not isinstance(p[1], bool)
                for p in stored)):
            return None
        params = {name: value for name, value in stored}
    model = _from_cache(key, params, flags)
    if model is None:
        return None
    model.times["description"] = model.times["derived_cache"]   # the marker of this path
    model.times["total"] = time.perf_counter() - t0
    return model if model_only else _system(model)
