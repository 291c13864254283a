"""The ground floor: names, errors, console lines, paths, atomic writes, provenance, interrupts,
list flags. Nothing here imports from another part of the package (tests/repo/test_import_graph.py),
so every layer may import it."""
