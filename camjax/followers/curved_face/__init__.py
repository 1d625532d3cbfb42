"""The translating curved-face (mushroom) follower: a crowned face of radius R_c on a sliding stem."""
