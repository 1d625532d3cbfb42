"""oscillating_roller follower."""
