"""The physical limits of a scenario's inputs, each once.

Scenarios (``testbench.scenario``) and study files (``studies.family``) check their values
against these; the runner checks every driven input against the min/max the FMU declares in
its model description. The limits here agree with those declarations (the Modelica source's
``min``/``max`` of the inputs; ``tests/repo/test_contracts.py`` reads the committed FMU's model
description and checks), so a value a scenario accepts is one the FMU accepts too.

Examples
--------
>>> MAX_RPM, MAX_FEED_MM_PER_MIN
(30000.0, 60000.0)
>>> COLDEST_AMBIENT_C < KELVIN_SUSPECT_C
True
"""

from __future__ import annotations

#: Fastest spindle a scenario or a study's speeds axis may ask for (rev/min): the model's
#: declared ``max`` of ``spindle_speed_rpm`` (high-speed spindles of machining centres reach
#: 30 000 rpm; the model's bearing losses are not meant beyond).
MAX_RPM = 30_000.0
#: The unit text of a speed range message: the bound is the FMU's, say so.
RPM_RANGE_UNIT = "rev/min (the FMU's declared range)"
#: Fastest mean feed (mm/min), the declared ``max`` of ``feed_x/y_mm_per_min``: 60 m/min is
#: the rapid traverse of fast machining centres; above it the feed-drive friction heat of the
#: model has no physical meaning.
MAX_FEED_MM_PER_MIN = 60_000.0
#: Ambient or sensor temperatures above this (°C) are almost certainly given in kelvin (the
#: model's ``ambient_C`` declares at most 80 °C).
KELVIN_SUSPECT_C = 60.0
#: Coldest ambient a workshop scenario may ask for (°C; the model declares at least -50 °C).
COLDEST_AMBIENT_C = -40.0
#: Largest offset (K) of a cooling setpoint that follows the ambient.
FOLLOW_AMBIENT_MAX_K = 20.0
#: Largest sensor noise and quantisation step (°C), probe noise and step (µm), offset fault (K).
MAX_NOISE_C, MAX_PROBE_NOISE_UM, MAX_OFFSET_C = 5.0, 100.0, 50.0
#: Largest probe drift (µm per √h for the walk, µm/h for the creep).
MAX_PROBE_DRIFT_UM = 100.0
#: Largest AR(1) lag-1 coefficient (1 would be a random walk, which has its own kind).
MAX_LAG1 = 0.9999
