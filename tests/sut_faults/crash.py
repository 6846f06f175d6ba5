"""Raises at its first observation (a crashing system under test)."""
import os, sys
sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "..", "examples", "python"))
from paracosm_sut import Controller, serve

class Crash(Controller):
    def act(self, obs):
        raise RuntimeError("controller exploded at t=%.2f" % obs.t_s)

serve(Crash())
