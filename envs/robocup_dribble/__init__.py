"""RoboCup 2D soccer simulator dribbling environment with heterogeneous players."""
