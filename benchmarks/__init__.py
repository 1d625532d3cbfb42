"""camjax benchmarks: ``python benchmarks/run.py [--quick] --out FILE.json`` (see run.py)."""
