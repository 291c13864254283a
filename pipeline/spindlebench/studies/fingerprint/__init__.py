"""The thermal fingerprint of a recording: ``statistics`` (the numbers), ``recordings`` (one
recording read with its column roles and fingerprinted), ``reference`` (the synthetic
machine's reference runs), ``figure``, and ``machine_check`` (each machine variant simulated
and its fingerprint checked against its targets). It sits above the testbench: the reference
and the check simulate.
"""
