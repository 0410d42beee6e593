"""The one door to the robot: the gateway (review, run, drive, the E-STOP), safety, the lease,
the sampler, the fleet, and the factory that picks the transport (astiop/transports)."""
