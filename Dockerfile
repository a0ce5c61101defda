# The same steps as the README: Debian bookworm, Debian's own ROS 1, the project's setup script.
FROM debian:bookworm
ENV DEBIAN_FRONTEND=noninteractive LP_NUM_THREADS=1
RUN apt-get update && apt-get install -y --no-install-recommends sudo ca-certificates && \
    rm -rf /var/lib/apt/lists/*
COPY . /asg
WORKDIR /asg
RUN bash scripts/setup.sh
RUN printf '#!/bin/bash\nset -e\nsource /asg/catkin_ws/devel/setup.bash\nexec "$@"\n' \
      > /entrypoint.sh && chmod +x /entrypoint.sh
ENTRYPOINT ["/entrypoint.sh"]
CMD ["bash", "scripts/train.sh"]
