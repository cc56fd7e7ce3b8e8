"""The ground floor of the package, used by every layer above it: the callback guard
(callback.py), argument checks (checks.py, validate.py), the status codes and their one
mapping to exceptions (status.py), the result records (result.py), the handle of a system
evaluated on the Fortran side (native.py) and the built-in parameter table it checks
(builtin_table.py), the check of a shared library before it is loaded (elf.py)."""
