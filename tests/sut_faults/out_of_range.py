"""Answers a throttle of 3, outside [-1, 1]."""
import os, sys
sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "..", "examples", "python"))
from paracosm_sut import Controller, serve

class Floor(Controller):
    def act(self, obs):
        return 3.0, 0.0

serve(Floor())
