"""The training loader resumes mid-epoch: its state continues the epoch's shuffled order."""

import torch
from torch.utils.data import Dataset

from keyin.data.datamodule import ClipDataModule


class Numbers(Dataset):
    def __len__(self) -> int:
        return 40

    def __getitem__(self, index: int) -> int:
        return index


def test_a_restored_train_loader_continues_the_epoch_where_it_stopped():
    torch.manual_seed(0)
    loader = ClipDataModule(Numbers(), Numbers(), batch_size=4, num_workers=0).train_dataloader()
    batches = iter(loader)
    seen = [next(batches) for _ in range(3)]
    state = loader.state_dict()
    rest = list(batches)
    torch.manual_seed(123)  # a resumed process has other random state
    restored = ClipDataModule(Numbers(), Numbers(), batch_size=4, num_workers=0).train_dataloader()
    restored.load_state_dict(state)
    continued = list(restored)
    assert [b.tolist() for b in continued] == [b.tolist() for b in rest]
    assert sorted(torch.cat(seen + continued).tolist()) == list(range(40))  # one epoch, nothing repeated
