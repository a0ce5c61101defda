"""How the long commands (campaign, plan) end on a signal. No ROS."""

import signal


def stop_on_signals():
    """SIGINT and SIGTERM raise KeyboardInterrupt, so that they end a command as Ctrl-C does (a
    campaign saves its state and `--resume` goes on). A command started in the background by a
    non-interactive shell has SIGINT ignored, and SIGTERM (kill, a plan being stopped, a CI's time
    limit) would otherwise end it at once."""

    def stop(signum, frame):
        raise KeyboardInterrupt

    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, stop)
