"""The CLC ranker's trained weights and card, installed as ``clc.models``."""
