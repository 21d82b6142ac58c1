"""Benchmarks: ``python -m rain_core.bench NAME`` runs rain_core/bench/NAME.py's ``main(argv)``.

Each benchmark prints a Markdown table of run time against error versus its reference and writes the table
and a plot (PNG) into the output folder (``--out``, default ``bench_out/``).
"""
