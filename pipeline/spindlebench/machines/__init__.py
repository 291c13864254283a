"""Machine variants (``variants``): a named set of parameter values for the model, and the
fingerprint targets the paper's machine is checked against. The testbench simulates a variant;
the fingerprint of its recordings and the check that runs it are ``studies.fingerprint``.
"""
