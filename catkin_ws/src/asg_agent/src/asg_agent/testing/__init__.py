"""Test support, not part of the running system (issue #80 item 5): the in-process stand-in for
the worker pool (fake_pool) and the campaign and suite commands on it (`python3 -m
asg_agent.testing.campaign EXPERIMENT --fake-workers N ...`, `python3 -m asg_agent.testing.suite run
SUITE --fake-workers N`). No module outside the tests imports it, but asg_analysis's ASP-effect
figure, which measures the search alone on the stand-in (a test checks the rule)."""
