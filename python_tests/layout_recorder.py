"""A stand-in for bpy's UILayout that records what a panel draws: the property names (for the
panel tests) and, when asked, the label text Blender would show beside each (for the real-UI
check that labels fit)."""


class Layout:
    """Records the properties a panel draws into `shown`, and their labels into `labels`."""

    def __init__(self, shown, labels=None):
        self.shown = shown
        self.labels = labels
        self.active = self.enabled = self.use_property_split = True

    def prop(self, data, name, text=None, **_):
        self.shown.append(name)
        if self.labels is not None:
            label = data.bl_rna.properties[name].name if text is None else text
            if label:
                self.labels.append(label)

    def prop_search(self, data, name, *_args, text=None, **_kwargs):
        self.prop(data, name, text=text)

    def row(self, **_):
        return self

    column = split = box = row

    def operator(self, *_args, **_kwargs):
        return self

    def label(self, **_):
        pass

    def template_list(self, *_args, **_kwargs):
        pass
