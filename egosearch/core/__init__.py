"""Plumbing every stage shares: checked output paths, staged writes, CSV reading, the machine's record, stale locks.
Imports nothing else of egosearch; any module may import it."""
