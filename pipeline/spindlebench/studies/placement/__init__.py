"""Virtual sensor placement (``spindlebench place``): which nodes of the model's temperature
field should carry the m sensors of a thermal-error model, by the paper's fuzzy clustering,
greedy forward selection and exhaustive search, judged across seasons.

The experiment family, executor, result store and seeds are the season sweep's; the selection
method is ``spindlebench.selection``'s. Modules: ``placement_file`` (the study file),
``candidates`` (recordings → virtual sensors), ``search`` (forward, exhaustive),
``placements`` (methods and scoring), ``schematic`` and ``placement_plots`` (figures),
``placement_report`` (README), ``placement_run`` (the study; its command is
``commands.place``).
"""
