"""Published cases and demo data: the numbers of the papers' benchmarks and the demo scenes.

Core packages never import this package; studies, the command line, examples, benchmarks and
tests do.
"""
