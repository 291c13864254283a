"""Virtual sensor placement (``spindlebench place``): which nodes of the model's temperature
field should carry the m sensors of a thermal-error model, by the paper's fuzzy clustering,
greedy forward selection and exhaustive search, judged across seasons.

The experiment family, executor, result store and seeds are the season sweep's; the selection
method is ``spindlebench.selection``'s. Modules: ``study`` (file), ``candidates`` (recordings →
virtual sensors), ``search`` (greedy, exhaustive), ``placements`` (methods and scoring),
``schematic`` and ``plots`` (figures), ``report`` (README), ``run`` (command).
"""
