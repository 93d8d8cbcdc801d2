"""Settings for the whole suite.

Property tests (hypothesis) draw the same examples on every run: a suite that
passes on one machine passes on CI, and a wrong answer hypothesis finds is
written down as a strict ``xfail`` with its example instead of failing some
runs at random.
"""

from hypothesis import settings

settings.register_profile("topomap", derandomize=True)
settings.load_profile("topomap")
