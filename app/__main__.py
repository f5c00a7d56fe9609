import os
import sys

from app import startup_gc

startup_gc.pause()                  # until the first picture (see app/startup_gc.py)

from app.cli import main  # noqa: E402  (after the pause: its imports are most of a start)

try:
    status = main(prog="python -m app")
    sys.stdout.flush()
except BrokenPipeError:
    # The reader went away (``python -m app stability --json | head``): not an error of ours.
    # Point stdout at /dev/null so that Python's own flush at exit does not complain again.
    os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
    status = 1
sys.exit(status)
