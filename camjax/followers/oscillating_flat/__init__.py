"""oscillating_flat follower."""
