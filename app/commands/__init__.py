"""The bodies of ``python -m app`` commands: animate (and the bundle of files its cluster jobs
ship), inspect, radiosity, stability, scale-out."""
