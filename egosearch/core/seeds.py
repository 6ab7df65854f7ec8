"""The largest seed a run takes: a training seeds numpy's legacy global generator, whose seeds are 32-bit."""

MAX_SEED = 2**32 - 1
"""numpy.random.seed's bound; a larger seed fails inside the run, after its work started."""
