"""The logic of one study or one page of docs/ each (no ROS): what a study computes that the
library's primitives (asg_analysis.exports, endpoints, stats, rules, campaign_metrics,
learning_curve, figures, replays, protocol) and its runner (asg_analysis.study, driven by the
study's protocol file) do not. A new study is a protocol file and, only where it has logic of its
own, a module here."""
