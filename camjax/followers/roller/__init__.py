"""roller follower."""
