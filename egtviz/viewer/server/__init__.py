"""The server edge: the ``egtviz serve`` CLI, the guards, the viser adapter, headless and browser helpers."""
