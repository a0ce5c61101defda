"""ros.stack_identity (issue #69): the workers a campaign resumes on must run its stack; the fp32
backends that are one function (channels_last, polyphase) count as one."""

import rospy

from asg_agent.ros import stack_identity as si


def _params(monkeypatch, backend):
    values = {
        "/w/segmenter/model": "/models/flawed.pt",
        "/w/segmenter/backend": backend,
    }
    monkeypatch.setattr(rospy, "get_param", lambda name, default=None: values.get(name, default))
    monkeypatch.setattr(rospy, "has_param", lambda name: name in values)


def test_a_channels_last_campaign_resumes_on_polyphase_workers_and_not_on_bf16(monkeypatch):
    settings = {"stack": "paper", "perception": "unet", "model": "flawed", "unet_backend": "channels_last"}
    _params(monkeypatch, "polyphase")
    assert si.stack_mismatch("/w", settings) == []
    _params(monkeypatch, "bf16")
    assert si.stack_mismatch("/w", settings) == [
        "the campaign's stack runs the 'channels_last' inference backend, /w runs 'bf16'"
    ]
    _params(monkeypatch, "channels_last")
    assert si.stack_mismatch("/w", dict(settings, unet_backend="polyphase")) == []
