"""Running the job: one map to its output files (:mod:`~topomap.run.job`), many maps at once
(:mod:`~topomap.run.batch`), the run record of an output folder (:mod:`~topomap.run.record`) and the
edits of an output folder (:mod:`~topomap.run.editing`).
"""
