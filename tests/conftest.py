"""Test-suite settings: hypothesis without wall-clock deadlines (CI machines are shared), derandomised in CI."""

import os

from hypothesis import settings

settings.register_profile("egtviz", deadline=None, print_blob=True)
settings.register_profile("egtviz-ci", deadline=None, print_blob=True, derandomize=True)
settings.load_profile("egtviz-ci" if os.environ.get("CI") else "egtviz")
