"""The oscillating curved-face follower: a crowned face of radius R_c on an arm swinging about a pivot."""
