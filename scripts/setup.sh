#!/usr/bin/env bash
# Install what is missing (Debian packages) and build the catkin workspace. Idempotent.
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
install_packages
build_workspace ON
log "setup done; use: source $WS/devel/setup.bash"
