"""The project's file formats, each defined in one module.

- ``tables``: the checked-TOML reader behind scenarios, studies, climates and paper configs.
- ``recording``: the recording CSV and its JSON sidecar, and every column-name rule.
- ``columns``: the column roles of a user's recording (time, sensors, CSV dialect).
"""
