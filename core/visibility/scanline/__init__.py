"""The scan-line visible-surface algorithm (FvDFH 15.6, Watkins): :mod:`.watkins`."""
