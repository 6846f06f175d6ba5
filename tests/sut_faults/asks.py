"""Asks in its hello for the sensors in argv[1] (JSON) and the control rate in argv[2]
(JSON: a number or null), then cruises: for hellos that cannot be honoured."""
import json, os, sys
sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "..", "examples", "python"))
from paracosm_sut import Controller, serve


class Asks(Controller):
    sensors = json.loads(sys.argv[1])
    control_hz = json.loads(sys.argv[2])

    def act(self, obs):
        return 0.3, 0.0


serve(Asks())
