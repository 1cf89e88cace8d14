"""Speed: the env's step against CartPole and against its own numpy path, in time, instructions and memory."""
