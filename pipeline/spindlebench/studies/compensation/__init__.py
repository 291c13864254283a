"""Compensation in the loop: the trained model in the controller, day after day.

``controller`` turns predictions into the offset an axis would apply (update interval, rate
limit, dead band) and detects sensor faults; ``loop`` simulates the days, trains, retrains and
scores the residual; ``compensation_file`` reads the study file, ``compensation_report``
writes the outputs; ``spindlebench compensate`` is ``commands.compensate``.
"""
