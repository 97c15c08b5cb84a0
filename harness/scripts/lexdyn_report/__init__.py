"""The nightly report of lexdyn runs (docs/report.md): reading stored results, the history of
past nights, matplotlib figures, the 3D replay data and the HTML page. Entry point:
harness/scripts/report.py."""
