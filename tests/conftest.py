"""Test-suite settings: hypothesis without wall-clock deadlines (CI machines are shared), derandomised in CI;
EGT figures kept in memory (an example script run by a test must not start a server and wait for Ctrl-C; a test
that wants the server sets ``EGTVIZ_FIGURE=on``)."""

import os

from hypothesis import settings

settings.register_profile("egtviz", deadline=None, print_blob=True)
settings.register_profile("egtviz-ci", deadline=None, print_blob=True, derandomize=True)
settings.load_profile("egtviz-ci" if os.environ.get("CI") else "egtviz")
os.environ.setdefault("EGTVIZ_FIGURE", "off")
