"""Plumbing every stage shares: checked output paths, staged runs, atomic CSVs, the machine's record, stale locks.
Imports nothing else of egosearch; any module may import it."""
