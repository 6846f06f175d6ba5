"""Answers every observation twice (a controller that writes its control on two code paths).
Both with and without --sut-fresh, the second answer must be caught, never applied a step late."""
import os, sys
sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "..", "examples", "python"))
import paracosm_sut
from paracosm_sut import Controller, serve

original = paracosm_sut.write_frame


def write_twice(stream, header, buffers=()):
    original(stream, header, buffers)
    if "throttle" in header:
        original(stream, header, buffers)


paracosm_sut.write_frame = write_twice


class Cruise(Controller):
    def act(self, obs):
        return 0.3, 0.0


serve(Cruise())
