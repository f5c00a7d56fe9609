import os
import sys

from app.cli import main

try:
    status = main()
    sys.stdout.flush()
except BrokenPipeError:
    # The reader went away (``python -m app stability --json | head``): not an error of ours.
    # Point stdout at /dev/null so that Python's own flush at exit does not complain again.
    os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
    status = 1
sys.exit(status)
