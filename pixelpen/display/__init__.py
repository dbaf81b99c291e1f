"""The common display abstraction: pictures, capabilities, the Display base class and the URL registry."""
