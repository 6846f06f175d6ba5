"""Answers with a control but no `step` (a protocol-1 client)."""
import os, sys
sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "..", "examples", "python"))
import paracosm_sut
from paracosm_sut import Controller, serve

original = paracosm_sut.write_frame


def write_without_step(stream, header, buffers=()):
    header = {k: v for k, v in header.items() if k != "step"}
    original(stream, header, buffers)


paracosm_sut.write_frame = write_without_step


class Cruise(Controller):
    def act(self, obs):
        return 0.3, 0.0


serve(Cruise())
