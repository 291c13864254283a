# ---
# jupyter:
#   jupytext:
#     formats: py:percent
#   kernelspec:
#     display_name: Python 3
#     language: python
#     name: python3
# ---

# %% [markdown]
# # 2. Which sensors matter
#
# A thermal-error model predicts the drift from a few temperatures, so the controller can
# move the tool back. Twenty sensors are expensive to fit and to keep working, and many of
# them say the same thing: two probes on the same warm part rise together. The method of
# Xu et al. (2023) picks a few sensors in four steps:
#
# 1. **Similarity.** How alike two sensors' curves are: the absolute correlation of their
#    rises, a number between 0 (unrelated) and 1 (the same shape). This is the *fuzzy
#    similarity matrix* R.
# 2. **Closure.** If A is like B and B is like C, A and C belong together too. The
#    *max-min transitive closure* t(R) makes the similarity transitive.
# 3. **λ-cut.** Keep the pairs whose closed similarity is at least a threshold η. The groups
#    that remain are clusters of sensors that say the same thing.
# 4. **ψ.** In each cluster, take the sensor most correlated with the drift (its ψ).
#
# The model is then a straight-line fit of the drift on the chosen sensors' rises. We
# build it on one day (the paper's January experiment) and test it on another (February,
# at half the speed).

# %%
import matplotlib.pyplot as plt
import numpy as np
from IPython.display import Image, display
from scipy.cluster.hierarchy import dendrogram
from spindlebench.commands import course
from spindlebench.commands.course import spindlebench
from spindlebench import (
    SCENARIOS_DIR,
    correlation_with,
    cut_for_clusters,
    cut_height,
    evaluate,
    linkage_from_similarity,
    read_recording,
    rises,
    similarity_matrix,
    transitive_closure,
)

work = course.start("02")


def quick_copy(name: str) -> str:
    """The paper's scenario with a 30 s communication step instead of 1 s (the same
    experiment, ~30 times faster; the drift differs by well under 1 µm)."""
    text = (SCENARIOS_DIR / "paper" / f"{name}.toml").read_text()
    path = work / f"{name}.toml"
    path.write_text(text.replace("step_s = 1.0", "step_s = 30.0"))
    return path


for name in ("exp1", "exp2"):
    spindlebench("simulate", quick_copy(name), "-o", work / f"{name}.csv", "-q")
spindlebench("plot", work / "exp1.csv", work / "exp2.csv", "--rises",
              "-o", work / "days.png")
display(Image(filename=work / "days.png"))

# %% [markdown]
# ## Step 1: the similarity matrix
#
# Each cell is the similarity of two sensors' rises on the training day. Bright blocks are
# groups of sensors that move together.

# %%
train = read_recording(work / "exp1.csv")
sensors = [f"T{i}" for i in range(1, 21)]
X = rises(train[sensors].to_numpy())
y = train["drift_um"].to_numpy()
R = similarity_matrix(X)
fig, ax = plt.subplots(figsize=(6, 5))
image = ax.imshow(R, vmin=np.floor(R.min() * 10) / 10, vmax=1.0, cmap="viridis")
ax.set_xticks(range(20), sensors, rotation=90, fontsize=7)
ax.set_yticks(range(20), sensors, fontsize=7)
fig.colorbar(image, label="similarity R (|correlation| of rises)")
ax.set_title("Fuzzy similarity of the 20 sensors, January run")
plt.show()
off_diagonal = R[~np.eye(20, dtype=bool)]
print(f"smallest similarity {off_diagonal.min():.2f}; "
      f"{(off_diagonal > 0.9).mean():.0%} of the pairs are above 0.9")

# %% [markdown]
# Every similarity is high (look at the colour scale): on a cold start every temperature
# rises, so every curve looks like every other. That is the first lesson of this notebook:
# **on one warm-up, the sensors are hard to tell apart**, and the method has little to work
# with.
#
# ## Steps 2 and 3: closure, dendrogram and the λ-cut
#
# The closure is drawn as a tree (a *dendrogram*): two branches join at the height
# 1 − t(R) where they become similar. Cutting the tree at 1 − η gives the clusters; the
# dashed line is the cut that leaves 3 clusters. It is drawn halfway between the last merge
# the cut keeps and the first it undoes, not at 1 − η itself: η equals one of the closed
# similarities, so 1 − η lies exactly on a merge and a line there would hide which side of
# it the cut falls (the legend gives η).

# %%
T = transitive_closure(R)
cut = cut_for_clusters(T, 3)
tree = linkage_from_similarity(T)
fig, ax = plt.subplots(figsize=(8, 3.8))
dendrogram(tree, labels=sensors, ax=ax, color_threshold=0, above_threshold_color="0.3",
           leaf_font_size=8)
ax.axhline(cut_height(tree[:, 2], cut.eta), color="tab:red", ls="--",
           label=f"λ-cut for 3 clusters (η = {cut.eta:.4f})")
ax.set_ylabel("1 − t(R)")
ax.legend()
plt.show()
for number, members in enumerate(cut.clusters, start=1):
    print(f"cluster {number}: {', '.join(sensors[i] for i in members)}")

# %% [markdown]
# ## Step 4: ψ, the correlation with the drift
#
# Within each cluster the method keeps the sensor whose rise is most correlated with the
# drift.

# %%
psi = correlation_with(X, y)
fig, ax = plt.subplots(figsize=(8, 2.8))
colours = ["tab:red" if i in [m[np.argmax(np.abs(psi[m]))] for m in cut.clusters] else "0.6"
           for i in range(20)]
ax.bar(sensors, psi, color=colours)
ax.set_ylim(min(0.9, psi.min() - 0.05), 1.0)  # zoom in on the range of ψ
ax.set_ylabel("ψ")
ax.set_title("Correlation of each sensor's rise with the drift (red: chosen per cluster)")
plt.show()

# %% [markdown]
# ## Train on January, predict February
#
# `evaluate` runs all four steps and the fit on the training recording, and scores the
# model on the test recording (RMSE: the typical size of the prediction error in µm).

# %%
february = {"February": work / "exp2.csv"}  # test recordings by the name results use
result = evaluate(work / "exp1.csv", february, "drift_um", k=3)
print("chosen:", result.selected, " RMSE on February:",
      f"{result.rmse_um['February']:.1f} µm")

# %% [markdown]
# ## Pick sensors by hand
#
# Is the method's choice better than a sensible guess? Try a few hand-picked pairs. With
# `k` equal to the number of sensors, every sensor is its own cluster, so `evaluate` keeps
# them all and only fits.

# %%
for pick in (["T1", "T10"], ["T1", "T8"], ["T6", "T10"], ["T4", "T16"]):
    by_hand = evaluate(work / "exp1.csv", february, "drift_um", sensors=pick, k=len(pick))
    print(f"{' + '.join(pick):9s} RMSE on February: {by_hand.rmse_um['February']:5.1f} µm")

# %%
prediction = result.predictions["February"]
measured = result.measured["February"]
hours = read_recording(february["February"])["time_s"] / 3600
fig, ax = plt.subplots(figsize=(8, 3))
ax.plot(hours, measured, "k", lw=2, label="measured drift, February")
ax.plot(hours, prediction, "tab:red", label=f"predicted from {', '.join(result.selected)}")
ax.set(xlabel="time (h)", ylabel="drift (µm)")
ax.legend()
ax.grid(alpha=0.3)
plt.show()

# %% [markdown]
# What to notice: a model that fits January well can still miss February by several µm,
# because February runs at half the speed, so the balance between spindle heat and room
# temperature is different. Which sensors "matter" depends on the days you train on.
#
# ## Exercises
#
# 1. Change the number of clusters to 2 and to 5. Which sensors join, and does the error
#    on February fall?
# 2. Train on February (`exp2.csv`) and test on January. Is the error the same both ways?
# 3. Find the best pair of sensors by trying all 190 pairs with `evaluate(..., sensors=pair,
#    k=2)`. Is the best pair one the method would ever choose?
