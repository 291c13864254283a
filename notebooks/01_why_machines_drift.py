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
# # 1. Why machine tools drift
#
# A machining centre is made of steel and cast iron. When the spindle turns, its bearings
# and its motor turn electrical and mechanical power into heat. The heat flows into the
# spindle shaft, the headstock, the column and the table, and every part that warms up
# grows a little: about 11 µm per metre and per kelvin. The tool tip moves relative to the
# workpiece. This movement is the **thermal error**, or *drift*. On a real machine it is
# often the largest error left after the geometry has been calibrated.
#
# In this notebook we run the synthetic machine of the testbench from a cold start, and
# look at three things:
#
# 1. the heat sources (watts),
# 2. the temperatures of the 20 sensors,
# 3. the growth of each part of the *structural loop* (the chain of parts from the tool to
#    the table), which adds up to the drift.
#
# Then we change the spindle speed and the room temperature and see what moves.
#
# Everything here uses the commands of the testbench (`spindlebench simulate`,
# `spindlebench plot`), called from Python so the notebook runs anywhere.

# %%
from pathlib import Path

import matplotlib.pyplot as plt
import pandas as pd
from IPython.display import Image, display

from spindlebench.commands import course
from spindlebench.commands.course import spindlebench
from spindlebench import read_recording

work = course.start("01")  # this notebook's own files: the folder it prints

# %% [markdown]
# ## A scenario: what the machine does
#
# A *scenario* is a small TOML file. This one says: 4 hours at 4000 rpm, both feed axes
# moving back and forth at 1500 mm/min, in a room that stays at 20 °C. The machine starts
# cold, at room temperature. The co-simulation exchanges inputs every 30 s and the virtual
# logger records every 2 minutes.

# %%
COLD_START = """
description = "4 h at {rpm} rpm from a cold start, room at {ambient}"
duration_s = 14400
step_s = 30.0
sample_interval_s = 120.0

[speed]
kind = "constant"
rpm = {rpm}

[feed]
kind = "constant"
x_mm_per_min = 1500
y_mm_per_min = 1500

[ambient]
{ambient_table}
"""


def scenario(name: str, rpm: int, ambient_table: str, ambient: str) -> Path:
    """Write a cold-start scenario file and return its path."""
    path = work / f"{name}.toml"
    path.write_text(COLD_START.format(rpm=rpm, ambient_table=ambient_table, ambient=ambient))
    return path


constant_20 = 'kind = "constant"\ntemperature_C = 20.0'
base = scenario("base", 4000, constant_20, "20 °C")
spindlebench("simulate", base, "-o", work / "base.csv", "--plot")
display(Image(filename=work / "base.png"))

# %% [markdown]
# The figure has four rows. The first two are temperatures, grouped by the part of the
# machine a sensor sits on (spindle front in reds, headstock in purples, X axis in blues,
# Y axis in greens, the air probe T10 in black). The third row is the drift, the fourth the
# inputs. Notice that the spindle-front sensors rise fast in the first hour and then
# slowly, while the feed-axis sensors keep climbing.
#
# ## Where the heat comes from
#
# Besides what the sensors measure, a synthetic recording also holds the *truth*: every
# heat flow of the model (`true_Q_…_W`) and every term of the drift (`true_…_um`). A real
# machine cannot tell you these.

# %%
run = read_recording(work / "base.csv")
hours = run["time_s"] / 3600
sources = ["true_Q_front_bearing_W", "true_Q_rear_bearing_W", "true_Q_spindle_motor_W",
           "true_Q_x_feed_W", "true_Q_y_feed_W"]
fig, ax = plt.subplots(figsize=(8, 3.5))
for column in sources:
    if column in run:
        ax.plot(hours, run[column], label=column.removeprefix("true_Q_").removesuffix("_W"))
ax.set(xlabel="time (h)", ylabel="heat (W)", title="Heat sources at 4000 rpm")
ax.legend(fontsize=8)
ax.grid(alpha=0.3)
plt.show()

# %% [markdown]
# The bearing heat *falls* during the first hour: as the bearing warms, its oil gets
# thinner and the friction drops. Together the sources are a few hundred watts, a small
# electric heater, acting on a few tonnes of iron for hours.
#
# ## The structural loop
#
# The drift is a signed sum around the loop: parts whose growth pushes the tool towards the
# table (spindle, tool, headstock, Z screw) or the table up towards the tool (table,
# fixture) add; parts whose growth lifts the head away (column, bed) subtract
# (`docs/model.md` lists every term). The recording has each term; we draw each one's
# growth with the signed sum.

# %%
terms = [c for c in run.columns
         if c.startswith("true_") and c.endswith("_um") and c != "true_drift_um"]
fig, ax = plt.subplots(figsize=(8, 3.8))
for column in terms:
    ax.plot(hours, run[column] - run[column].iloc[0], label=column[5:-3])
total = run["true_drift_um"] - run["true_drift_um"].iloc[0]
ax.plot(hours, total, "k", lw=2.5, label="drift (the signed sum)")
ax.set(xlabel="time (h)", ylabel="growth since the start (µm)",
       title="Each term of the structural loop")
ax.legend(fontsize=8, loc="upper left")
ax.grid(alpha=0.3)
plt.show()
print(f"drift after 4 h: {total.iloc[-1]:.1f} µm")

# %% [markdown]
# ## Change the speed and the room
#
# Now two more runs: the same machine at 2000 rpm, and at 4000 rpm in a room that warms
# from 12 °C to 22 °C during the run (a spring morning). `spindlebench plot` draws the three
# recordings side by side, as *rises* (change since the start), so the shapes compare.

# %%
slow = scenario("slow", 2000, constant_20, "20 °C")
warming = scenario("warming_room", 4000,
                   'kind = "season"\nlow_C = 12.0\nhigh_C = 22.0\nstart_hour = 8\n'
                   'trough_hour = 8\npeak_hour = 12', "12-22 °C")
for path in (slow, warming):
    spindlebench("simulate", path, "-o", work / f"{path.stem}.csv", "-q")
spindlebench("plot", *(work / f"{n}.csv" for n in ("base", "slow", "warming_room")),
              "--rises", "-o", work / "compare.png")
display(Image(filename=work / "compare.png"))

# %%
for name in ("base", "slow", "warming_room"):
    recording = read_recording(work / f"{name}.csv")
    print(f"{name:13s} drift after 4 h: {recording['drift_um'].iloc[-1]:5.1f} µm, "
          f"T1 rise {recording['T1'].iloc[-1] - recording['T1'].iloc[0]:4.1f} K")

# %% [markdown]
# Where did the warming room's extra heat go? Each term after 4 hours, in both runs:

# %%
ends = {}
for name in ("base", "warming_room"):
    recording = read_recording(work / f"{name}.csv")
    ends[name] = {c[5:-3]: recording[c].iloc[-1] - recording[c].iloc[0] for c in terms}
growth = pd.DataFrame(ends).round(1)
growth["difference"] = growth["warming_room"] - growth["base"]
growth

# %% [markdown]
# What to notice:
#
# - Half the speed gives much less heat in the bearings, and so a smaller drift.
# - A warming room warms the *whole* machine, also the parts far from the spindle, and the
#   sensors rise much more. But the room makes parts on **both** sides of the loop grow:
#   the table shows which terms gained, and how much of that the column takes back. The
#   drift changes far less than the temperatures. A model that reads the rise of a
#   spindle sensor as drift would be fooled by the room.
#
# ## Exercises
#
# 1. Run the base scenario for 8 hours (`duration_s = 28800`). Does the drift level off?
#    Which term of the structural loop is still growing at the end?
# 2. Stop the spindle after 2 hours (`[speed] kind = "steps"`,
#    `steps = [{at_s = 0, rpm = 4000}, {at_s = 7200, rpm = 0}]`). How fast does the drift
#    come back, and which sensors cool first?
# 3. Start the warming-room run in the afternoon, when the room cools (`start_hour = 15`,
#    `trough_hour = 6`, `peak_hour = 14`). Which sign does the column term take now?
