"""An external system under test that sees through the camera, for the `camera/external` bench
(scenarios/benches/simulate.rs): it asks for pilotnet's camera (320 x 240 at 10 Hz), reads every
frame's brightness under the road ahead, and holds 12 m/s with a proportional throttle. What
the bench measures is the protocol's cost (a frame of 230 KB each way per decision), not a
driver."""
import os, sys
sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "..", "examples", "python"))
from paracosm_sut import Controller, serve

class Camera(Controller):
    sensors = {"camera": {"width": 320, "height": 240, "rate_hz": 10}}
    control_hz = 10.0

    def act(self, obs):
        rgb = bytes(obs.camera())
        # The mean of one row near the bottom of the image: the road under the bonnet.
        row = rgb[3 * 320 * 200:3 * 320 * 201]
        _ = sum(row) / len(row)
        speed = obs.ego["speed_mps"]
        return max(-1.0, min(1.0, 0.5 * (12.0 - speed))), 0.0

serve(Camera())
