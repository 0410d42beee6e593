"""A recorded session (MCAP) played back as a read-only robot."""
