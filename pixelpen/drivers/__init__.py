"""Transports that move bytes: serial (pyserial URLs), USB printer class (pyusb), recording and replaying traces."""
