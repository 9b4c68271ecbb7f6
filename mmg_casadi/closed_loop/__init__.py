"""The closed loop: state and parameter layout, the symbolic step, its compiled rollouts, outcomes."""
