"""VDA 5050 LIF layouts (Layout Interchange Format): the reader and the writer."""
