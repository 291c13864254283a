"""The command line only: one module per sub-command (``register(subparsers)`` adds it), the
shared argument helpers (``arguments``) and the dispatcher (``main``). No domain logic lives
here, and no domain module imports from here (tests/repo/test_import_graph.py)."""
