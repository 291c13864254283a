"""The shared vocabulary: sensor names, the paper's six, group and similarity names, units.

One home for every name that more than one layer (model/, testbench/, selection/, studies/)
uses, so a rename is one edit. This module imports nothing from the package, so
every layer may import it without importing another layer.
"""

from __future__ import annotations

#: The paper's twenty temperature sensors (Xu et al. 2023, Fig. 4), in the paper's order.
SENSORS: tuple[str, ...] = tuple(f"T{i}" for i in range(1, 21))
#: The paper's six-sensor subset (spindle front, headstock, motor, ambient, X motor, Y motor).
PAPER_SIX: tuple[str, ...] = ("T1", "T6", "T8", "T10", "T13", "T16")

#: The paper's three candidate groups: reference group 1 (all raw sensors), reference group 2
#: (the six raw sensors) and the reconstructed group (the six plus their pairwise differences).
#: Used in every table, file name and report (paper study and season sweep alike).
ALL_RAW, SIX_RAW, SIX_DIFF = "all_raw", "six_raw", "six_diff"
GROUPS: tuple[str, ...] = (ALL_RAW, SIX_RAW, SIX_DIFF)
#: Human-readable group labels for figure legends.
GROUP_LABELS: dict[str, str] = {
    ALL_RAW: "all raw",
    SIX_RAW: "six raw",
    SIX_DIFF: "six + differences",
}

#: The two readings of the paper's eq. 1 (see ``selection.similarity``); the first is the default.
SIMILARITIES: tuple[str, ...] = ("abs-pearson", "literal")
DEFAULT_SIMILARITY = SIMILARITIES[0]

#: How ``evaluate`` treats missing (NaN) values: one-line error, or drop incomplete samples
#: (also a key of ``paper_study.toml``).
MISSING_MODES: tuple[str, ...] = ("error", "drop-rows")

#: The model's and the FMU's name: ``models/SpindleBench.mo`` builds ``fmus/SpindleBench.fmu``
#: (``core.paths`` finds it, ``model`` builds it).
FMU_NAME = "SpindleBench"

#: The fingerprint statistics of a recording (``studies.fingerprint.statistics``), in the
#: order they are reported (also their JSON keys and a machine file's ``[[target]]``
#: statistics, ``machines.variants``).
FINGERPRINT_KEYS: tuple[str, ...] = (
    "best_raw_psi",
    "best_single_r2",
    "best_diff_psi",
    "best_pair_r2",
    "t63_ratio",
    "t63_fastest_ratio",
    "overshoot",
    "early_fraction",
)

#: Degrees Celsius to kelvin.
KELVIN_OFFSET = 273.15

#: The paper's selection method. Every method's name, line and kind is in the one registry,
#: ``selection.method_registry.METHOD_REGISTRY`` (``spindlebench methods`` prints it).
DEFAULT_METHOD = "closure"
#: The method that keeps every candidate (k does not apply).
ALL_CANDIDATES = "all-candidates"
#: The joint selection of several targets that is the union of their own selections
#: (``selection.multi_target``; the other joint selections are the registry's multi-output
#: methods).
JOINT_UNION = "union"
#: The choice of one candidate inside a cluster.
WITHIN: dict[str, str] = {
    "psi": "largest |psi|, the Pearson correlation with the error (the paper's eq. 4)",
    "grey": "largest grey relational grade with the error (Deng; interval normalisation, "
            "rho = 0.5)",
    "ga": "a genetic algorithm picks one member per cluster, minimising the RMSE of OLS "
          "trained on the first half of the run and scored on the second (population 30, "
          "40 generations, seeded)",
}
DEFAULT_WITHIN = "psi"
#: The regression after the selector (all on rises; the first three linear).
REGRESSORS: dict[str, str] = {
    "ols": "ordinary least squares with intercept (the paper's MLR)",
    "ridge": "ridge on standardised rises, penalty by 5-fold CV over contiguous time blocks "
             "(widened once, warned, at the grid's edge)",
    "pls": "partial least squares (scikit-learn PLSRegression, up to 2 components)",
    "gbr": "gradient boosting (scikit-learn GradientBoostingRegressor, 100 trees of depth 3, "
           "seeded); nonlinear",
    "mlp": "a small neural network (scikit-learn MLPRegressor, one hidden layer of 16, "
           "standardised inputs, seeded); nonlinear",
    "tf1": "identified first-order transfer function from the speed programme (dynamic: "
           "reads time and speed, not the selected rises)",
    "tf2": "identified second-order transfer function from the speed programme (dynamic)",
    "network": "identified grey-box thermal network from the speed programme, 1-3 nodes by "
               "leave-one-cycle-out, the room constant (dynamic)",
    "network-ambient": "the same network with the recording's ambient as a second input "
                       "(dynamic)",
    "observer": "steady-state Kalman filter on a network identified on the error and the "
                "selected rises: reads the speed programme and those rises (dynamic)",
}
#: The regressors that are dynamic models of a recording's time axis (issue 22,
#: ``identification``): besides the selected rises they read the recording's time and its
#: speed programme (and ``network-ambient`` its ambient); ``selection.dynamic`` hands them over.
DYNAMIC_REGRESSORS: tuple[str, ...] = ("tf1", "tf2", "network", "network-ambient", "observer")
#: The regressors whose model is ``intercept + rises @ coefficients``.
LINEAR_REGRESSORS: tuple[str, ...] = ("ols", "ridge", "pls")
DEFAULT_REGRESSOR = "ols"
#: The seed of the seeded methods (fcm, kmeans, stability, mi, mrmr, ga, gbr, mlp) unless a
#: command is given another.
DEFAULT_METHOD_SEED = 0
#: The largest seed of the seeded methods (fcm, kmeans, stability): scikit-learn's and NumPy's
#: legacy generators take 0 .. 2**32 - 1 (a larger one was a traceback deep inside them).
MAX_METHOD_SEED = 2**32 - 1
