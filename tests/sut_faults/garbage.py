"""Answers the handshake, then prints text to stdout instead of a frame."""
import os, sys
sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "..", "examples", "python"))
from paracosm_sut import Controller, serve

class Garbage(Controller):
    def act(self, obs):
        sys.stdout.buffer.write(b"debug: throttle=1\n" * 4)
        sys.stdout.buffer.flush()
        return 0.0, 0.0

serve(Garbage())
