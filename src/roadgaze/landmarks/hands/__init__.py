"""Hands beside the face: MediaPipe's palm detector and hand landmark model on LiteRT, tracked
across frames (`engine`), the graph's rules (`graph`), the models' provisioning (`models`) and
the driver's hands as the record carries them (`stage`)."""
