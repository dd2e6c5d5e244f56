"""Model reduction: Craig-Bampton bases, modal derivatives and their selection, the blade's builder."""
