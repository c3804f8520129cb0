"""What a designer reads: CSV tables, summary.json, the output folder written whole, and the figures
(:mod:`sewgen.report.plots`). Reads the machine layer, the engine and the leaves.
"""
