"""Plumbing every stage shares: checked paths, staged runs, atomic CSVs, the machine, stale locks, registries.
Imports nothing else of egosearch; any module may import it."""
