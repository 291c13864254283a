"""The paper's own numbers (Xu et al. 2023, Chin. J. Sci. Instrum., Tables 4-6 and eq. 5).

Transcribed from the published text so our tables can print them beside ours. Group keys:
``all_raw`` = reference group 1 (参照组 1, all 20 raw sensors), ``six_raw`` = reference group 2
(参照组 2, T1, T6, T8, T10, T13, T16), ``six_diff`` = the reconstructed group (重构组, those six
plus their 15 differences). The paper writes differences as ``T1~T10``; we write ``T1-T10``.
"""

from __future__ import annotations

from spindlebench.core.names import ALL_RAW, SIX_DIFF, SIX_RAW

CLUSTERS: tuple[int, ...] = (2, 3, 4)
#: Table 6 trains on experiment 1 and predicts experiments 2-5.
TRAIN_EXPERIMENT = "exp1"
TEST_EXPERIMENTS: tuple[str, ...] = ("exp2", "exp3", "exp4", "exp5")
#: Group keys of the tables below: ``spindlebench.core.names.GROUPS``.

#: Table 4: selected points and their ψ, per number of clusters (the paper prints |ψ|-sized,
#: positive values; the order is the paper's row order).
SELECTED: dict[int, dict[str, list[tuple[str, float]]]] = {
    2: {
        ALL_RAW: [("T1", 0.9126), ("T17", 0.8028)],
        SIX_RAW: [("T1", 0.9126), ("T16", 0.7867)],
        SIX_DIFF: [("T1-T10", 0.9961), ("T13-T16", 0.9816)],
    },
    3: {
        ALL_RAW: [("T1", 0.9126), ("T17", 0.8028), ("T8", 0.8215)],
        SIX_RAW: [("T1", 0.9126), ("T16", 0.7867), ("T8", 0.8215)],
        SIX_DIFF: [("T1-T10", 0.9961), ("T13-T16", 0.9816), ("T8-T10", 0.9519)],
    },
    4: {
        ALL_RAW: [("T1", 0.9126), ("T17", 0.8028), ("T8", 0.8215), ("T7", 0.7005)],
        SIX_RAW: [("T1", 0.9126), ("T16", 0.7867), ("T8", 0.8215), ("T10", 0.6080)],
        SIX_DIFF: [
            ("T1-T10", 0.9961), ("T13-T16", 0.9816), ("T8-T10", 0.9519), ("T6-T10", 0.9409),
        ],
    },
}

#: Table 5: training R² of the regression on experiment 1.
R2: dict[int, dict[str, float]] = {
    2: {ALL_RAW: 0.9701, SIX_RAW: 0.9786, SIX_DIFF: 0.9943},
    3: {ALL_RAW: 0.9748, SIX_RAW: 0.9836, SIX_DIFF: 0.9963},
    4: {ALL_RAW: 0.9940, SIX_RAW: 0.9837, SIX_DIFF: 0.9963},
}

#: Table 6: RMSE (µm) predicting experiments 2-5 with the model trained on experiment 1,
#: then the mean as printed.
RMSE_UM: dict[int, dict[str, tuple[float, float, float, float, float]]] = {
    2: {
        ALL_RAW: (15.6, 4.5, 4.1, 20.1, 11.1),
        SIX_RAW: (9.1, 10.6, 2.7, 18.6, 10.3),
        SIX_DIFF: (1.5, 2.2, 5.8, 4.9, 3.6),
    },
    3: {
        ALL_RAW: (19.9, 7.5, 4.9, 15.9, 12.1),
        SIX_RAW: (9.3, 16.3, 3.6, 13.6, 10.7),
        SIX_DIFF: (2.4, 5.6, 4.4, 5.3, 4.4),
    },
    4: {
        ALL_RAW: (3.5, 13.3, 4.3, 5.6, 6.7),
        SIX_RAW: (1.9, 14.1, 3.9, 18.5, 9.6),
        SIX_DIFF: (2.2, 5.7, 4.0, 4.5, 4.1),
    },
}

#: Eq. 5: the 2-cluster models (µm, ΔT in K).
MODELS_K2: dict[str, str] = {
    ALL_RAW: "y = -5.2 + 8.9·ΔT1 - 21.9·ΔT17",
    SIX_RAW: "y = -4.6 + 8.5·ΔT1 - 21.7·ΔT16",
    SIX_DIFF: "y = -0.7 + 4.9·(ΔT1 - ΔT10) - 8.4·(ΔT13 - ΔT16)",
}

CITATION = (
    "Xu K., Wang W., Li Z., Li G., Miao E. (2023). Temperature-sensitive point selection "
    "method of machine tool based on active construction of temperature difference variable. "
    "Chinese Journal of Scientific Instrument. DOI 10.19650/j.cnki.cjsi.J2210389"
)
