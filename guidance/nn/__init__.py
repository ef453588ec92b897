"""Transformer networks of T-SCvx: model, training, ONNX export, onnxruntime inference."""
