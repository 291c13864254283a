"""The season sweep: run, summary, figures and report."""
