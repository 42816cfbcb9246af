"""The paper's experiments: head-control methods behind one interface and their registry,
fixed-seed evaluation with 95% intervals, the localisation-error comparison, episode traces
and the run report."""
