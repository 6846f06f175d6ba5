"""Client library for paracosm's external system-under-test protocol (SUT_PROTOCOL.md).

Standard library only; numpy is used when installed, to view images without a copy.

Write a controller with ``sensors``, ``reset`` and ``act``, then call ``serve``::

    from paracosm_sut import Controller, serve

    class Cruise(Controller):
        sensors = {"lidar": True}
        def act(self, obs):
            return 0.5 * (10.0 - obs.ego["speed_mps"]), 0.0

    serve(Cruise())

Run it with ``paracosm-fuzz SCENARIO --sut-cmd "python3 my_controller.py"``. Never print to
stdout: it carries the protocol. Print to stderr instead; paracosm shows the last lines of
stderr when the process fails.
"""

import json
import struct
import sys

try:
    import numpy as np
except ImportError:  # numpy is optional
    np = None

PROTOCOL_VERSION = 2

_DTYPES = {"uint8": 1, "float32": 4}


def read_frame(stream):
    """Reads one frame: returns ``(header, buffers)``, or ``None`` at the end of the stream.

    ``buffers`` maps each buffer's name to ``(data, dtype, shape)``, ``data`` a bytearray.
    """
    prefix = stream.read(4)
    if len(prefix) < 4:
        return None
    (length,) = struct.unpack("<I", prefix)
    header = json.loads(stream.read(length).decode("utf-8"))
    buffers = {}
    for spec in header.get("buffers", []):
        data = bytearray(stream.read(spec["nbytes"]))
        if len(data) != spec["nbytes"]:
            raise EOFError("truncated buffer " + spec["name"])
        buffers[spec["name"]] = (data, spec["dtype"], tuple(spec["shape"]))
    return header, buffers


def write_frame(stream, header, buffers=()):
    """Writes one frame: ``header`` (a dict) as JSON, then the raw bytes of ``buffers``."""
    text = json.dumps(header, allow_nan=False).encode("utf-8")
    stream.write(struct.pack("<I", len(text)))
    stream.write(text)
    for b in buffers:
        stream.write(b)
    stream.flush()


class Observation:
    """One control step's observation.

    ``t_s`` (s), ``ego`` (``pos_m`` [x, y, z] in m, ``heading_rad``, ``speed_mps``, and
    ``set_speed_mps`` when the scenario gives the ego a speed to keep), and the
    sensors asked for in the handshake: ``camera()`` (height x width x 3, uint8, row-major,
    top-left origin), ``depth()`` (height x width float32 metres along the optical axis, inf
    for sky), ``lidar()`` (n x 3 float32 points [forward, up, right] in m, vehicle frame).
    """

    def __init__(self, header, buffers):
        self.t_s = header["t_s"]
        self.ego = header["ego"]
        self._buffers = buffers

    def _array(self, name):
        if name not in self._buffers:
            return None
        data, dtype, shape = self._buffers[name]
        if np is not None:
            return np.frombuffer(data, dtype=dtype).reshape(shape)
        if dtype == "float32":
            values = struct.unpack("<%df" % (len(data) // 4), data)
            if len(shape) == 2 and name == "lidar":
                return [values[i:i + 3] for i in range(0, len(values), 3)]
            return values
        return data

    def camera(self):
        """The RGB image: a numpy array (h, w, 3), or the raw bytes without numpy."""
        return self._array("camera")

    def depth(self):
        """The depth map in metres: a numpy array (h, w), or a flat tuple without numpy."""
        return self._array("depth")

    def lidar(self):
        """Lidar points [forward, up, right] in metres: (n, 3), or a list of triples."""
        return self._array("lidar")


class Controller:
    """Base class of a system under test. Override ``sensors``, ``control_hz``, ``reset`` and
    ``act``."""

    #: Sensors wanted: {"camera": {"width": 320, "height": 240, "focal_mm": 24, ...} or True,
    #: "depth": bool, "lidar": bool}. See SUT_PROTOCOL.md for every camera field.
    sensors = {}
    #: Decisions per simulated second; None decides at every physics step (60 Hz).
    control_hz = None

    def reset(self, seed):
        """Starts a new test; ``seed`` drives any randomness."""

    def act(self, obs):
        """Returns ``(throttle, steering)``, each in [-1, 1]."""
        raise NotImplementedError


def serve(controller, stdin=None, stdout=None):
    """Answers paracosm's messages until it closes the stream."""
    stdin = stdin or sys.stdin.buffer
    stdout = stdout or sys.stdout.buffer
    while True:
        frame = read_frame(stdin)
        if frame is None:
            return
        header, buffers = frame
        kind = header.get("type")
        if kind == "hello":
            write_frame(stdout, {"type": "hello", "sensors": controller.sensors,
                                 "control_hz": controller.control_hz})
        elif kind == "reset":
            controller.reset(header["seed"])
            write_frame(stdout, {"type": "ready"})
        elif kind == "observation":
            throttle, steering = controller.act(Observation(header, buffers))
            write_frame(stdout, {"step": header["step"], "throttle": float(throttle),
                                 "steering": float(steering)})
        else:
            raise ValueError("unknown message type %r" % kind)


class LidarBrake(Controller):
    """The example controller: cruise at the scenario's set speed (12 m/s without one) and
    brake at full force when a lidar return in the 1.3 m corridor ahead is closer than the
    1.4 s time headway plus 2 m, like the built-in ``aeb`` on a straight road (no lane
    keeping)."""

    sensors = {"lidar": True}

    def act(self, obs):
        speed = obs.ego["speed_mps"]
        nearest = min((p[0] - 2.25 for p in obs.lidar()
                       if p[0] > 0.0 and abs(p[2]) <= 1.3 and p[1] >= -0.6), default=None)
        if nearest is not None and nearest - 2.0 < max(speed, 0.0) * 1.4:
            return -1.0, 0.0
        target = obs.ego.get("set_speed_mps", 12.0)
        return max(-1.0, min(1.0, 0.5 * (target - speed))), 0.0


if __name__ == "__main__":
    serve(LidarBrake())
