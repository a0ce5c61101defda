"""The ground floor the upper floors read: experiments, registered stacks, the scenario store,
exports, failure modes and scenes of stored rows, stage-cost readings (no ROS, no search)."""
