"""Answers NaN controls (written as a JSON string, the only way JSON can carry NaN)."""
import json, os, struct, sys
sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "..", "examples", "python"))
import paracosm_sut
from paracosm_sut import Controller, serve

def write_nan(stream, header, buffers=()):
    if "throttle" in header:
        text = b'{"throttle": NaN, "steering": 0.0}'
        stream.write(struct.pack("<I", len(text)) + text)
        stream.flush()
    else:
        original(stream, header, buffers)

original = paracosm_sut.write_frame
paracosm_sut.write_frame = write_nan

class Nan(Controller):
    def act(self, obs):
        return 0.0, 0.0

serve(Nan())
