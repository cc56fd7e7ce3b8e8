"""The two shapes of conmech's results.

- :class:`DictResult`: a dict whose keys are also attributes (SciPy's ``OdeResult`` and
  ``OptimizeResult`` are such dicts): the results of the integrators, which users unpack
  and extend.
- :class:`Record`: a fixed set of attributes (``__slots__``) filled from keywords, those
  not given None: equilibria, orbits, branches, families; :class:`StatusRecord` adds
  ``success`` (``status == 0``, elementwise for an array) to those with a status.
"""

__all__ = ["DictResult", "Record", "StatusRecord"]


class DictResult(dict):
    """A dict whose keys are also attributes; a missing key is an AttributeError."""

    def __getattr__(self, name):
        try:
            return self[name]
        except KeyError as exc:
            raise AttributeError(name) from exc

    __setattr__ = dict.__setitem__
    __delattr__ = dict.__delitem__

    def __dir__(self):
        return list(self.keys())


class Record:
    """Attributes named by ``__slots__`` (of the class and its bases), set from keywords;
    those not given are None."""

    __slots__ = ()

    def __init__(self, **kw):
        for cls in type(self).__mro__:
            for k in getattr(cls, "__slots__", ()):
                if not hasattr(self, k):
                    setattr(self, k, kw.get(k))


class StatusRecord(Record):
    """A record with a ``status`` (0 = success, as the Fortran codes): ``success``."""

    __slots__ = ()

    @property
    def success(self):
        """status == 0 (elementwise for an array of statuses)."""
        return self.status == 0
