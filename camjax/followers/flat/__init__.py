"""flat follower."""
