"""The paper's comparison (Xu et al. 2023, section 3) on any set of recordings.

``config`` says what to run, ``analysis`` runs it on ``spindlebench.selection``,
``paper_tables`` and ``figures`` render the analogues of the paper's Tables 4-6 and Figures
3-6, ``paper_report`` writes them with a README and provenance, ``reference`` holds the paper's
own numbers. The command is ``commands.paper``.
"""
