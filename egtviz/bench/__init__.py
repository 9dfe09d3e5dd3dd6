"""``egtviz bench``: speed measurements (``core``, ``viewer``, ``servo``, ``classroom``); see ``docs/benchmarks.md``."""
