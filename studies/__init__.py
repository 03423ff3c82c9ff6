"""Studies and reports on the generated models: operation counts, scaling, the embeddable C, work-precision,
the stress suite, the fuzz study, benchmarks and the chart-switching figures.  They import codegen and
runtime; neither imports them.

    python -m studies --help          # the studies, one line each
    python -m studies stress --quick  # any of them, with its own options
"""
