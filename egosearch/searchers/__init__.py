"""The searchers that are not learned: oracle, random, the classical frontier searcher, and their registry.
Imports sim/ and core/; imported by runs/, rl/ (a teacher), motion/ and the CLI; its registry, plain data that
imports nothing, by every stage (``registry``: the one place a searcher is added)."""
