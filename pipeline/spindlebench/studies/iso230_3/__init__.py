"""ISO 230-3 thermal tests (``spindlebench iso230-3``): the tests as scenarios, their
evaluation in the standard's form (drift against time per direction beside the temperatures,
ranges, ETVE, the stability criterion) and the report (figure, JSON, CSV with provenance),
for the synthetic machine and for a real recording with a map of its channels.

Modules: ``evaluation`` (pure numbers from time series), ``channels`` (which columns are which
direction: the synthetic recording's, or a MAP.toml's), ``figure``, ``command``.
"""
