"""egosearch: a reproducible benchmark for learned egocentric object search."""

import sys

__version__ = "0.1.0"

if "gymnasium" in sys.modules:
    # gymnasium.make("egosearch:EgoSearch-v0") imports this package: register the ids for it. Only when
    # gymnasium is loaded, so that reading the stored results (egosearch.report) loads no env library;
    # `import egosearch.envs` registers them in any order.
    import egosearch.envs  # noqa: F401
