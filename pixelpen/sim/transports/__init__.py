"""The host-facing ends of simulated devices: the paced serial port, pyserial's sim:// handler, a pty, a pyusb backend."""
