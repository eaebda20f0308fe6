"""What an export could not carry over, said once per kind in Blender's report (and on the
console in the background): nothing is dropped in silence."""


class Report:
    def __init__(self):
        self.lines = []

    def add(self, line):
        if line not in self.lines:
            self.lines.append(line)

    def send(self, engine):
        for line in self.lines:
            if engine is not None:
                engine.report({"WARNING"}, "bounce: " + line)  # Blender also prints it in the background
            else:
                print("bounce:", line)
