"""Running the job: one map to its output files (:mod:`~topomap.run.job`), many maps at once
(:mod:`~topomap.run.batch`).
"""
