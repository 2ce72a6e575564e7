"""The evaluation block: episode sets, the benchmark, statistics, throughput measurements, plots."""
