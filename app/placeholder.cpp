namespace flexirob::app { int placeholder() { return 0; } }
