"""knife-edge follower."""
