"""Running the chunks of a sweep: in this process, as Dask tasks, or resumed from
checkpoints. Reads `sweep.kernels` and `sweep.grid`; imports nothing above."""
