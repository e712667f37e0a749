"""The driver's upper body: MediaPipe's pose detector and pose landmark model (BlazePose) on
LiteRT, tracked across frames (`engine`), the graph's rules (`graph`) and the models' files
(`models`)."""
