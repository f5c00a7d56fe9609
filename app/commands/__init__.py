"""The bodies of ``python -m app`` commands: animate, inspect, radiosity, stability, scale-out."""
