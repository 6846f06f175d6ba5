"""Shared by the scipy scripts: run the calling script inside its own virtualenv with scipy.

`ensure_venv(script)` re-executes `script` inside ${VENV:-/tmp/paracosm-scipy-venv}, creating
it and installing scipy and numpy on first use; inside the virtualenv it returns at once.
"""

import os
import subprocess
import sys
import venv
from pathlib import Path

VENV_DIR = Path(os.environ.get("VENV", "/tmp/paracosm-scipy-venv"))


def ensure_venv(script):
    """Re-execute `script` inside VENV_DIR (creating it if needed)."""
    if Path(sys.prefix).resolve() == VENV_DIR.resolve():
        return
    python = VENV_DIR / "bin" / "python"
    if not python.exists():
        print(f"creating virtualenv at {VENV_DIR}", file=sys.stderr)
        venv.create(VENV_DIR, with_pip=True)
        subprocess.check_call([str(python), "-m", "pip", "install", "-q", "scipy", "numpy"])
    os.execv(str(python), [str(python), str(Path(script).resolve()), *sys.argv[1:]])
