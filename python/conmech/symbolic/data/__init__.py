"""Robot descriptions shipped with conmech (URDF): ``arm7.urdf``, a seven-joint arm for the
examples and the benchmarks (:func:`conmech.symbolic.urdf.data_path` gives the path)."""
