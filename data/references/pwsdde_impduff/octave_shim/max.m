function varargout = max(varargin)
% Octave 7's max has no 'all': max(x, [], 'all') is max(x(:)).
if nargin == 3 && ischar(varargin{3}) && strcmp(varargin{3}, 'all')
  [varargout{1:builtin("max",nargout,1)}] = builtin('max', varargin{1}(:));
else
  [varargout{1:builtin("max",nargout,1)}] = builtin('max', varargin{:});
end
end
