"""The project's file formats, each defined in one module.

- ``tables``: the checked-TOML reader behind scenarios, studies, climates and paper configs.
"""
