"""Measuring the methods: benchmark data sets, scoring, simulated maps of floor plans."""
