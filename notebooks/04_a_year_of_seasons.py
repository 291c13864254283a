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
# # 4. A year of seasons
#
# A thermal-error model is trained once, on one day, and then used for months. The room is
# cold in January and warm in July; the machine runs fast on some jobs and slowly on
# others. A model is only useful if it keeps working on days it was not trained on.
#
# `spindlebench sweep` tests exactly that. It simulates a family of days (months ×
# speeds × random weather), trains each selection method on one day and predicts all the
# others. For every method we get one error (RMSE, in µm) per held-out day. Two questions:
#
# - **Lower**: is the typical error (the median over the held-out days) small?
# - **Stable**: is the error about the same on every day, or is it small on some and
#   large on others? We measure that by the spread of the errors (the interquartile
#   range, IQR: the width of the middle half of them) and by the worst day.
#
# This notebook runs a small sweep (16 short days) so it finishes in about a minute. The
# full study, `scenarios/studies/season_sweep.toml`, runs 120 six-hour days.

# %%
import matplotlib.pyplot as plt
import pandas as pd
from IPython.display import Image, display

from spindlebench.commands import course
from spindlebench.commands.course import spindlebench

work = course.start("04")

STUDY = """
[study]
name = "course-seasons"
seed = 4
replicas = 2                     # two random days per month and speed
climate = "chongqing"            # the paper's city: cold winters, hot summers

[experiment]
duration_h = 3.0
step_s = 120.0
sample_interval_s = 120.0
start_hour = 8.0                 # every day starts cold at 08:00
weather_sd_C = 1.5               # day-to-day scatter around the month's normal weather

[axes]
months = ["Jan", "Apr", "Jul", "Oct"]
speeds_rpm = [2000, 4000]
noise = ["lab"]

[noise.lab]
noise_C = 0.05
quantum_C = 0.1

[training]
rule = "one"                     # one training day, like the paper: January, 4000 rpm
month = "Jan"
speed_rpm = 4000

[methods]
clusters = [2, 3]
groups = ["all_raw", "six_raw", "six_diff"]
baselines = ["top-k-correlated"]
"""
study = work / "seasons.toml"
study.write_text(STUDY)
spindlebench("sweep", study, "-o", work / "sweep", "--workers", "0")  # in this process

# %% [markdown]
# The sweep writes one row per (method, k, held-out day) into `results.csv`, a README
# with its verdict, and figures. We read the table ourselves.

# %%
results = pd.read_csv(work / "sweep" / "results.csv")
results["k"] = results["k"].astype("Int64")  # a whole number (a column with gaps reads as float)
measured = results[(results["data"] == "measured") & results["error"].isna()]
print(len(measured), "scores;", measured["test_experiment"].nunique(), "held-out days")
measured[["test_experiment", "method", "k", "rmse_um", "selected"]].head()

# %% [markdown]
# ## The spread per method
#
# Each box holds the errors of one method over all held-out days: the line is the median,
# the box the middle half, the whiskers the rest.

# %%
labels, groups = [], []
for (method, k), table in measured.groupby(["method", "k"]):
    labels.append(f"{method}\nk = {k}")
    groups.append(table["rmse_um"].to_numpy())
fig, ax = plt.subplots(figsize=(10, 4))
ax.boxplot(groups, tick_labels=labels)
ax.set_ylabel("held-out RMSE (µm)")
ax.set_title("Error on days the model was not trained on")
ax.grid(axis="y", alpha=0.3)
plt.setp(ax.get_xticklabels(), fontsize=8)
plt.show()

# %% [markdown]
# ## Lower and stable, as numbers

# %%
def iqr(values: pd.Series) -> float:
    return float(values.quantile(0.75) - values.quantile(0.25))


summary = measured.groupby(["method", "k"])["rmse_um"].agg(
    median="median", IQR=iqr, worst="max").round(2)
summary.sort_values("median")

# %% [markdown]
# ## What varies: the held-out month and speed
#
# The same errors split by the month and the speed of the held-out day. A model trained
# in January at 4000 rpm has to *extrapolate* to July (warm) and to 2000 rpm (less heat).

# %%
table = measured[measured["k"] == 2].pivot_table(
    index=["test_speed_rpm", "test_month"], columns="method", values="rmse_um",
    aggfunc="median").round(2)
table

# %%
print("best method (k = 2) for each kind of held-out day:")
print(table.idxmin(axis=1).to_string())

# %%
display(Image(filename=work / "sweep" / "plots" / "rmse_by_month.png"))

# %% [markdown]
# What to notice: the table above says which method is best on each kind of held-out day.
# When the best method changes with the speed or the month of the day it predicts, no
# single number ranks the methods. The median says which is lower on a typical day; the
# IQR and the worst day say how much it varies from day to day: that is what "stable"
# means, and a study over many days is needed to answer either question.
#
# ## Exercises
#
# 1. Add a start-stop programme (`programmes = ["constant", "start-stop"]` under `[axes]`
#    and a `[programmes.start-stop]` table with `kind = "cycles"`, `on_min = 50`,
#    `off_min = 10`). Which methods suffer most?
# 2. Train on each season instead of January only (`[training] rule = "each-season"`,
#    `speed_rpm = 4000`). Does the spread shrink?
# 3. Add the shop-floor noise level (`noise_C = 0.3`) as a second `[noise.shop]` entry. Do
#    the difference methods become more or less stable?
