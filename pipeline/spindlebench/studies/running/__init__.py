"""Running study tasks: the executor (isolated local or dask workers), the content-addressed
result store, the simulation and evaluation jobs."""
