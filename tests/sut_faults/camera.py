"""Asks for a 64 x 48 camera and depth, checks what arrives, and coasts (a throttle of 0.3 would
carry the car past the end of the 200 m road within the 15 s test, which the default
OffRoadMonitor fails)."""
import os, sys
sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "..", "examples", "python"))
from paracosm_sut import Controller, serve

class Camera(Controller):
    sensors = {"camera": {"width": 64, "height": 48, "focal_mm": 24.0}, "depth": True}
    control_hz = 10.0

    def act(self, obs):
        rgb, depth = obs.camera(), obs.depth()
        n = 64 * 48
        size = lambda a: a.size if hasattr(a, "size") else len(a)
        if size(rgb) != 3 * n or size(depth) != n:
            raise RuntimeError("wrong sizes %d %d" % (size(rgb), size(depth)))
        # Send the mean brightness back through stderr for the test to see.
        sys.stderr.write("frame t=%.2f mean=%.1f\n" % (obs.t_s, sum(bytes(rgb)) / (3 * n)))
        return 0.0, 0.0

serve(Camera())
