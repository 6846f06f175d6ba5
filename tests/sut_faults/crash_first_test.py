"""Crashes in the first test it sees (the file named by CRASH_MARKER does not exist yet),
then behaves: shows that the next test gets a fresh process."""
import os, sys
sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "..", "examples", "python"))
from paracosm_sut import LidarBrake, serve

marker = os.environ["CRASH_MARKER"]

class CrashOnce(LidarBrake):
    def act(self, obs):
        if not os.path.exists(marker):
            open(marker, "w").close()
            os._exit(7)
        return LidarBrake.act(self, obs)

serve(CrashOnce())
