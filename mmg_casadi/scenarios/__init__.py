"""Scenarios: scenario files, the maritime-schema interchange, the paper's encounters and Imazu's problems, the scenario runner."""
