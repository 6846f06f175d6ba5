"""Never answers an observation (a hung system under test)."""
import os, sys, time
sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "..", "examples", "python"))
from paracosm_sut import Controller, serve

class Hang(Controller):
    def act(self, obs):
        time.sleep(3600)

serve(Hang())
