"""The searchers that are not learned: oracle, random and the classical frontier searcher.
Imports sim/ and core/; imported by runs/, rl/ (a teacher), motion/ and the CLI."""
