"""The Monte Carlo study: sampling plan, execution, results, statistics and failure mechanisms."""
